// The paint_renderer node/nodelet (one class behind a node main and a nodelet): shows the object being
// painted (thesis 5.7). It keeps a copy of the paint model's active surfels (PaintedCloudMirror) from the
// latched full cloud and the per-tick deltas, renders it with differential updates (only the surfels a delta
// removed and added are un-splatted and splatted, only the touched tiles normalised again; a full update when
// the camera or the object moved, when a delta is large, after a sequence gap, or when precision asks for
// it), draws the brush and its shadow over the image, and publishes the images as csg_renderer does. The
// camera follows tf.
//
// Subscribes  surfels/painted (sensor_msgs/PointCloud2 with normals, radii, colours and `father`, in
//             fixed_frame: the paint model's world_frame), surfels/painted_delta (relaxed_connectivity/
//             PaintDelta), brush/skin (PointCloud2 in fixed_frame; draw_brush)
// Publishes   ~image (sensor_msgs/Image rgb8), ~depth (32FC1, metres, NaN background), ~camera_info (latched,
//             header frame = camera_frame), ~stats (relaxed_connectivity/PaintRenderStats, every
//             stats_period)
// Services    ~save_image (relaxed_connectivity/PaintFile: writes the current image as PNG)
// Parameters  (private) fixed_frame ("world"), camera_frame ("paint_camera", REP 103 optical), max_rate
//             ([Hz] 60), pose_tolerance (1e-6 m / rad), width, height, horizontal_fov (degrees), near_clip,
//             far_clip, ewa_filter, lowpass_variance, cutoff_radius, depth_tolerance_scale, exact_footprint,
//             exact_silhouettes, shading, backface_culling, threads, background [r g b], max_delta_surfels,
//             max_tile_updates, environment ("studio" | "none" | an equirectangular PNG: reflective
//             paint, 5.7), draw_brush, shadow, light_direction [x y z], shadow_length, shadow_strength,
//             stats_period ([s] 1); see config/paint_session.yaml.
//
// A frame is published when something changed (a delta, the brush, the camera), at most max_rate times per
// second; deltas are applied as they arrive and rendered at once when a frame is due (else within a quarter
// of a frame period: the camera and the brush are polled at 4 max_rate). Bad input (malformed or non-finite
// clouds, a delta naming a surfel's father it does not list, a frame other than fixed_frame) is logged,
// counted and rejected; the image and the copy stay as they were.
#pragma once

#include <dynamic_reconfigure/server.h>
#include <relaxed_connectivity/PaintDelta.h>
#include <relaxed_connectivity/PaintFile.h>
#include <relaxed_connectivity/SplatConfig.h>
#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>

#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "relaxed_connectivity/core/latency_histogram.h"
#include "relaxed_connectivity/core/surfel_cloud.h"
#include "relaxed_connectivity/paint/painted_cloud_mirror.h"
#include "relaxed_connectivity/render/splat/camera.h"
#include "relaxed_connectivity/render/splat/differential_renderer.h"
#include "relaxed_connectivity/render/splat/environment_map.h"
#include "relaxed_connectivity/render/splat/overlay_compositor.h"
#include "relaxed_connectivity/ros/node_diagnostics.h"

namespace rc {

struct PaintRendererParams {
  std::string fixed_frame = "world";
  std::string camera_frame = "paint_camera";
  double max_rate = 60.0;
  double stats_period = 1.0;
  int width = 1280, height = 720;
  double horizontal_fov = 60.0;  ///< degrees
  double near_clip = 0.01, far_clip = 100.0;
  DifferentialRenderConfig render;
  /// Environment reflected by metallic paint (5.7): "studio" (procedural), "none", or an equirectangular PNG.
  std::string environment = "studio";
  bool draw_brush = true;
  OverlayOptions brush;

  /// Throws std::invalid_argument naming the parameter and the bad value.
  void validate() const;
  Camera camera() const;
};

/// Reads the private parameters (defaults: PaintRendererParams{}) and validates them.
PaintRendererParams readPaintRendererParams(const ros::NodeHandle& private_nh);

class PaintRenderer {
 public:
  PaintRenderer(ros::NodeHandle nh, ros::NodeHandle private_nh);
  ~PaintRenderer();

  void paintedCallback(const sensor_msgs::PointCloud2ConstPtr& msg);
  void deltaCallback(const relaxed_connectivity::PaintDeltaConstPtr& msg);
  void skinCallback(const sensor_msgs::PointCloud2ConstPtr& msg);
  bool saveImage(relaxed_connectivity::PaintFile::Request& request,
                 relaxed_connectivity::PaintFile::Response& response);
  /// Looks up the camera; renders and publishes a frame if anything changed. Returns true if it did.
  bool renderIfChanged();

 private:
  struct AppliedDelta {  // kept a while: a full cloud that arrives late is followed by the deltas after it
    ros::Time stamp;
    uint32_t generation;
    std::vector<uint32_t> originals;
    SurfelCloud surfels;
  };
  void reject(const std::string& what, const std::string& reason);
  /// Replaces the copy by a full cloud stamped `stamp` and applies the kept deltas of its generation after
  /// it.
  void resync(const SurfelCloud& cloud, const ros::Time& stamp);
  void applyDelta(const std::vector<uint32_t>& originals, const SurfelCloud& surfels,
                  const ros::Time& pose_stamp);
  /// A cloud of a message in fixed_frame (throws naming the problem).
  SurfelCloud cloudOf(const sensor_msgs::PointCloud2& msg, const char* what, bool need_father) const;
  void timerCallback(const ros::WallTimerEvent&);
  /// dynamic_reconfigure: new splat settings, a full update next ("settings"); refused settings are answered
  /// back with the ones that stay.
  void reconfigure(relaxed_connectivity::SplatConfig& config, uint32_t level);
  /// Renders if something changed and the last frame is at least 1 / max_rate old (one thread at a time).
  void renderWhenDue();
  void publishStats(const ros::WallTime& now);

  ros::NodeHandle nh_, private_nh_;
  PaintRendererParams params_;
  tf2_ros::Buffer tf_buffer_;
  tf2_ros::TransformListener tf_listener_;
  ros::Subscriber painted_sub_, delta_sub_, skin_sub_;
  ros::Publisher image_pub_, depth_pub_, info_pub_, stats_pub_;
  ros::ServiceServer save_srv_;
  ros::WallTimer timer_;

  std::mutex mutex_;  // everything below (nodelet managers call back from several threads)
  PaintedCloudMirror mirror_;
  bool have_object_ = false;
  std::unique_ptr<EnvironmentMap> environment_;  ///< (before renderer_: its configuration points here)
  DifferentialSurfelRenderer renderer_;
  OverlayCompositor compositor_;
  SurfelCloud pending_removed_, pending_added_;  ///< deltas since the last frame
  std::vector<ros::Time> pending_pose_stamps_;
  std::deque<AppliedDelta> recent_deltas_;
  uint64_t last_sequence_ = 0;
  ros::Time last_delta_stamp_;
  bool gap_ = false;      ///< a delta was missed: the copy is wrong until the next full cloud
  ros::Time copy_stamp_;  ///< of the full cloud the copy was last made from
  uint32_t copy_generation_ = 0;
  bool generation_known_ = false;
  bool waiting_ = false;     ///< deltas of a new object arrived: wait for its full cloud
  ros::Time waiting_stamp_;  ///< the new object's first full cloud is stamped this or later
  bool resynced_ = false;    ///< the copy was replaced: the next frame is a full update
  bool dirty_ = true;        ///< something to show since the last frame
  SurfelCloud skin_;
  std::vector<Rgba> composed_;  ///< the image with the brush
  std::optional<Camera> last_camera_;
  std::mutex frame_mutex_;    // renderWhenDue: one frame at a time
  ros::WallTime last_frame_;  ///< start of the last frame (frame_mutex_)

  // Stats of the current period
  ros::WallTime last_stats_;
  uint32_t frames_ = 0, full_updates_ = 0, differential_updates_ = 0, deltas_ = 0, delta_surfels_ = 0;
  uint32_t sequence_gaps_ = 0, resyncs_ = 0, rejected_ = 0;
  double full_ms_ = 0, differential_ms_ = 0, differential_max_ms_ = 0, brush_ms_ = 0;
  std::vector<double> latencies_ms_;
  LatencyHistogram session_latency_;  ///< since start
  std::string last_reason_ = "none", last_error_;

  NodeDiagnostics diagnostics_;  // the painted-cloud and delta inputs on /diagnostics
  // dynamic_reconfigure (config/dynamic_reconfigure/Splat.cfg), started last and stopped first.
  std::unique_ptr<dynamic_reconfigure::Server<relaxed_connectivity::SplatConfig>> reconfigure_server_;
};

}  // namespace rc
