// The paint_model node/nodelet: the object being painted (PaintSurface, thesis 5.3) and the brush the haptic
// device holds (5.4), stepped in the main loop (Fig. 5.4) with the latest device pose. It hands the contact
// parameters to the haptic_driver's 1 kHz force loop, which therefore never queries the surface. With a paint
// type it also transfers paint every tick (5.5: paint buffer, exchange, resampling of the object), dries the
// object's paint in bounded slices (5.6.1) and publishes the painted object. Diffusion, downsampling in the
// node, undo and the services are the next pieces.
//
// Subscribes  surfels (sensor_msgs/PointCloud2 with normals, any frame with a tf path to world_frame): the
//             object; each message replaces it (the kd-tree is built once per object)
//             <device>/pose (geometry_msgs/PoseStamped, the device's stylus pose, frame e.g. haptic_base)
// Publishes   brush_contact (relaxed_connectivity/BrushContact, in the pose frame, every main-loop tick)
//             brush/skeleton (visualization_msgs/MarkerArray), brush/skin (PointCloud2), both in world_frame
//             surfels/painted (PointCloud2, latched: the active surfels with visible colours, the paint
//             columns and `father`, at most painted_rate per second while paint changes)
// Parameters  (private) brush (preset file, required), device ("haptic"), world_frame ("world"), rate (main
//             loop [Hz], 60; the brush holds still at the latest pose until a new one arrives),
//             collision_passes (1), plane_proxy (true), proxy_reach (0.25), skin_rate ([Hz], 30; 0: off),
//             paint (paint type file, config/paint/paints/; empty: no paint transfer), pixel_size ([m], 0:
//             the brush's skin spacing), pressure_per_depth ([1/m], 2000), painted_rate ([Hz], 1),
//             drying_visits (originals dried per tick, 2000; 0: no drying); see
//             config/paint/brush_demo.yaml.
#pragma once

#include <geometry_msgs/PoseStamped.h>
#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>

#include <memory>
#include <mutex>
#include <string>

#include "relaxed_connectivity/paint/brush.h"
#include "relaxed_connectivity/paint/paint_dryer.h"
#include "relaxed_connectivity/paint/paint_transfer.h"

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

  /// Throws std::invalid_argument naming the parameter and the bad value.
  void validate() const;
};

/// Reads the private parameters once (defaults: PaintModelParams{}) and validates them.
PaintModelParams readPaintModelParams(const ros::NodeHandle& private_nh);

class PaintModel {
 public:
  /// Reads the parameters and the brush preset (throws std::invalid_argument / BrushPresetError), subscribes
  /// and advertises, starts the main loop.
  PaintModel(ros::NodeHandle nh, ros::NodeHandle private_nh);

  void surfelsCallback(const sensor_msgs::PointCloud2ConstPtr& msg);
  void poseCallback(const geometry_msgs::PoseStampedConstPtr& msg);
  /// One main-loop tick: advances the brush to the latest pose, publishes contact and visuals.
  void tick(const ros::WallTimerEvent& event);

 private:
  ros::NodeHandle nh_, private_nh_;
  PaintModelParams params_;
  tf2_ros::Buffer tf_buffer_;
  tf2_ros::TransformListener tf_listener_;
  std::mutex mutex_;                       // surface_, latest_pose_ (callbacks) against tick()
  std::shared_ptr<PaintSurface> surface_;  // painted by tick() only
  std::unique_ptr<PaintType> paint_type_;
  std::unique_ptr<PaintDryer> dryer_;
  ros::WallTime start_;
  bool painted_dirty_ = false;
  ros::WallTime last_painted_;
  std::unique_ptr<Brush> brush_;
  geometry_msgs::PoseStampedConstPtr latest_pose_;
  bool brush_placed_ = false;
  ros::WallTime last_skin_;
  unsigned long instabilities_ = 0;
  ros::Subscriber surfels_sub_, pose_sub_;
  ros::Publisher contact_pub_, skeleton_pub_, skin_pub_, painted_pub_;
  ros::WallTimer timer_;
};

}  // namespace rc
