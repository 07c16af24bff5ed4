// The paint_model node/nodelet: the object being painted (PaintSurface, thesis 5.3) and the brush the haptic
// device holds (5.4), stepped in the main loop (Fig. 5.4) with the latest device pose. It hands the contact
// parameters to the haptic_driver's 1 kHz force loop, which therefore never queries the surface. With a paint
// type it also transfers paint every tick (5.5: paint buffer, exchange, resampling of the object), dries
// (5.6.1), diffuses (5.6.2, paint types with D > 0) and downsamples (5.5.2) the object in bounded slices,
// journals every stroke for undo/redo, autosaves, and publishes the painted object: small deltas every tick,
// the full cloud at painted_rate.
//
// Subscribes  surfels (sensor_msgs/PointCloud2 with normals, any frame with a tf path to world_frame): the
//             object. While the object holds paint, another one is refused (logged, counted) unless
//             replace_painted is set or ~clear was called: nothing painted is lost by a stray message.
//             <device>/pose (geometry_msgs/PoseStamped, the device's stylus pose, frame e.g. haptic_base)
// Publishes   brush_contact (relaxed_connectivity/BrushContact, in the pose frame, every main-loop tick)
//             brush/skeleton (visualization_msgs/MarkerArray), brush/skin (PointCloud2), both in world_frame
//             surfels/painted (PointCloud2, latched: the active surfels with visible colours, the paint
//             columns and `father`, at most painted_rate per second while paint changes, and at once after
//             a load, undo, redo or clear)
//             surfels/painted_delta (relaxed_connectivity/PaintDelta: the originals changed this tick and
//             their surfels, a viewer's channels without the paint columns)
//             paint_stats (relaxed_connectivity/PaintStats, every stats_period seconds)
// Services    ~undo, ~redo, ~clear (relaxed_connectivity/PaintCommand), ~save, ~load, ~set_paint, ~set_brush
//             (relaxed_connectivity/PaintFile); dynamic_reconfigure (~set_parameters,
//             config/dynamic_reconfigure/Paint.cfg): the brush's physical parameters (a change rebuilds the
//             brush at rest; a Verlet step above the explicit limit is refused) and the paint's rates, shown
//             as loaded from the files
// Actions     ~load_state (relaxed_connectivity/LoadPaintedState: ~load with progress feedback)
// Parameters  (private) brush (preset file, required), device ("haptic"), world_frame ("world"), rate (main
//             loop [Hz], 60; the brush holds still at the latest pose until a new one arrives),
//             collision_passes (1), plane_proxy (true), proxy_reach (0.25), skin_rate ([Hz], 30; 0: off),
//             paint (paint type file, config/paint/paints/; empty: no paint transfer), pixel_size ([m], 0:
//             the brush's skin spacing), pressure_per_depth ([1/m], 2000), painted_rate ([Hz], 1),
//             drying_visits (originals dried per tick, 2000; 0: no drying), downsampling_visits (originals
//             with children looked at per tick, 200; 0: off), diffusion_surfels (active surfels around the
//             wet ones diffused per time step when the paint diffuses, 4000; 0: off), stroke_gap ([s]
//             without contact that ends a stroke, 0.25), journal_bytes (undo memory, 256 MiB), restore (a
//             state saved by ~save to load at start, ""), autosave (file, ""), autosave_period ([s], 60),
//             resume (false: with true, an autosave file that exists at start is loaded, so a node restarted
//             after a crash or kill (respawn="true") goes on from its last autosave),
//             replace_painted (false), stats_period ([s], 1), tf_wait ([s] a cloud waits for the transform of
//             its frame before it is refused, 30: a session's transforms may start late), palette (a palette
//             file, config/paint/palettes/, appended beside each object from the topic; ""); see
//             config/paint/brush_demo.yaml.
#pragma once

#include <actionlib/server/simple_action_server.h>
#include <dynamic_reconfigure/server.h>
#include <geometry_msgs/PoseStamped.h>
#include <relaxed_connectivity/LoadPaintedStateAction.h>
#include <relaxed_connectivity/PaintCommand.h>
#include <relaxed_connectivity/PaintConfig.h>
#include <relaxed_connectivity/PaintFile.h>
#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>

#include <atomic>
#include <boost/thread/recursive_mutex.hpp>
#include <memory>
#include <mutex>
#include <string>

#include "relaxed_connectivity/paint/brush.h"
#include "relaxed_connectivity/paint/paint_downsampling.h"
#include "relaxed_connectivity/paint/paint_dryer.h"
#include "relaxed_connectivity/paint/paint_journal.h"
#include "relaxed_connectivity/paint/paint_palette.h"
#include "relaxed_connectivity/paint/paint_transfer.h"
#include "relaxed_connectivity/paint/painted_surface_io.h"
#include "relaxed_connectivity/paint/surface_diffusion.h"
#include "relaxed_connectivity/ros/bounded_tf_filter.h"
#include "relaxed_connectivity/ros/node_diagnostics.h"

namespace rc {

struct PaintModelParams {
  std::string brush;
  std::string device = "haptic";
  std::string world_frame = "world";
  double rate = 60.0;
  BrushOptions brush_options;
  double skin_rate = 30.0;
  std::string paint;  ///< paint type file; empty: the brush does not paint
  PaintTransferOptions transfer;
  double painted_rate = 1.0;
  int drying_visits = 2000;
  int downsampling_visits = 200;
  int diffusion_surfels = 4000;
  double stroke_gap = 0.25;
  int journal_bytes = 256 << 20;
  std::string restore;
  std::string autosave;
  double autosave_period = 60.0;
  bool resume = false;
  bool replace_painted = false;
  double stats_period = 1.0;
  double tf_wait = 30.0;
  std::string palette;  ///< palette file (config/paint/palettes/); empty: none
  std::string object;   ///< a surfel file (.ply, .pcd, .xyz with normals) painted instead of the topic's

  /// Throws std::invalid_argument naming the parameter and the bad value.
  void validate() const;
};

/// Reads the private parameters once (defaults: PaintModelParams{}) and validates them.
PaintModelParams readPaintModelParams(const ros::NodeHandle& private_nh);

class PaintModel {
 public:
  /// Reads the parameters, the brush preset and the paint type (throws std::invalid_argument /
  /// BrushPresetError / PaintTypeError), restores a saved state if asked (throws IoError), subscribes and
  /// advertises, starts the main loop.
  PaintModel(ros::NodeHandle nh, ros::NodeHandle private_nh);
  ~PaintModel();

  /// A new object; its transform to world_frame is taken at `tf_time` (the cloud's stamp, which the message
  /// filter has seen transformable, or ros::Time(0): the latest, for a cloud stamped before the transforms
  /// kept).
  void surfelsCallback(const sensor_msgs::PointCloud2ConstPtr& msg, ros::Time tf_time);
  void poseCallback(const geometry_msgs::PoseStampedConstPtr& msg);
  /// One main-loop tick: advances the brush to the latest pose, paints, runs the background work, publishes.
  void tick(const ros::WallTimerEvent& event);

 private:
  using Command = relaxed_connectivity::PaintCommand;
  using File = relaxed_connectivity::PaintFile;
  bool undo(Command::Request&, Command::Response& res);
  bool redo(Command::Request&, Command::Response& res);
  bool clear(Command::Request&, Command::Response& res);
  bool save(File::Request& req, File::Response& res);
  bool load(File::Request& req, File::Response& res);
  bool setPaint(File::Request& req, File::Response& res);
  bool setBrush(File::Request& req, File::Response& res);
  /// dynamic_reconfigure (Paint.cfg): applies what holds and answers with it in `config`.
  void reconfigure(relaxed_connectivity::PaintConfig& config, uint32_t level);
  /// Shows the current brush and paint settings on the reconfigure server (model_mutex_ not held).
  void publishSettings();
  /// Replaces the brush (model_mutex_ held): loaded with the paint type, at rest at the next pose.
  void installBrush(std::unique_ptr<Brush> brush);
  void loadState(const relaxed_connectivity::LoadPaintedStateGoalConstPtr& goal);
  /// Loads a saved state (outside the model lock) and installs it; returns the message for the caller and in
  /// *active_surfels the count as installed (the main loop's downsampling may change it right after).
  bool loadFrom(const std::string& path, const LoadProgress& progress, std::string* message,
                size_t* active_surfels = nullptr);

  /// Installs a new object (model_mutex_ held): a fresh journal, dryer and downsampler; publishes it whole.
  void installSurface(std::unique_ptr<PaintSurface> surface, const std::string& what);
  void setPaintType(std::unique_ptr<PaintType> paint);
  /// (Re)creates the dryer and the diffusion for paint_type_ (what the paint does not need stays off).
  void restartBackgroundWork();
  void publishPainted(const ros::Time& stamp);
  void publishDelta(const ros::Time& stamp);
  void publishStats(const ros::WallTime& now);
  void autosave(const ros::WallTime& now);
  bool painted() const;

  ros::NodeHandle nh_, private_nh_;
  PaintModelParams params_;
  tf2_ros::Buffer tf_buffer_;
  tf2_ros::TransformListener tf_listener_;
  NodeDiagnostics diagnostics_;  // the object and pose inputs on /diagnostics
  std::mutex input_mutex_;       // latest_pose_ (callbacks) against tick()
  geometry_msgs::PoseStampedConstPtr latest_pose_;
  // The model: tick(), the services and surfelsCallback (to install an object) under model_mutex_.
  std::mutex model_mutex_;
  std::unique_ptr<PaintSurface> surface_;
  size_t object_hash_ = 0;  // of the surfels message surface_ came from (0: loaded from a file)
  std::string object_frame_;
  ros::Time object_cloud_stamp_;  // of that message: an older one (a late message filter failure) is ignored
  std::unique_ptr<PaintJournal> journal_;  // observes surface_ (destroyed before it)
  std::unique_ptr<PaintType> paint_type_;
  std::unique_ptr<PaletteSpec> palette_;
  std::unique_ptr<PaintDryer> dryer_;
  std::unique_ptr<PaintDownsampler> downsampler_;
  std::unique_ptr<SurfaceDiffusion> diffusion_;
  std::unique_ptr<Brush> brush_;
  bool brush_placed_ = false;
  int idle_ticks_ = 0;
  ros::WallTime start_;
  bool painted_dirty_ = false, publish_now_ = false;
  ros::WallTime last_painted_, last_skin_, last_autosave_, last_stats_;
  uint64_t delta_sequence_ = 0;
  ros::Time pose_stamp_;            ///< of the device pose of the latest brush step
  uint32_t object_generation_ = 0;  ///< counts objects installed (PaintDelta.object_generation)
  ros::Time object_stamp_;          ///< stamp of the current object's first full cloud
  bool new_object_ = false;
  // Stats over the current period.
  unsigned long events_ = 0, ticks_ = 0, instabilities_ = 0;
  std::atomic<unsigned long> rejected_{0};  // also counted by the pose callback
  unsigned long dropped_surfels_ = 0;
  double brush_s_ = 0, transfer_s_ = 0, background_s_ = 0, publish_s_ = 0;
  ros::Subscriber pose_sub_;
  // The object: clouds on `surfels` through a tf2_ros::MessageFilter to world_frame (waits bounded by
  // tf_wait).
  std::unique_ptr<BoundedTfFilter> surfels_input_;
  void refuseSurfels(const std::string& reason);  // counted, logged, in /diagnostics
  ros::Publisher contact_pub_, skeleton_pub_, skin_pub_, painted_pub_, delta_pub_, stats_pub_;
  std::vector<ros::ServiceServer> services_;
  ros::WallTimer timer_;
  std::unique_ptr<actionlib::SimpleActionServer<relaxed_connectivity::LoadPaintedStateAction>> load_action_;
  // ~set_parameters (dynamic_reconfigure), started with the settings of the loaded files.
  boost::recursive_mutex reconfigure_mutex_;  // the server's (updateConfig needs one it does not own)
  std::unique_ptr<dynamic_reconfigure::Server<relaxed_connectivity::PaintConfig>> reconfigure_server_;
};

}  // namespace rc
