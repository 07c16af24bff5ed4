// The scanner node: publishes sensor_msgs/PointCloud2 scans, either read from files (looping) or rendered by
// a simulated depth sensor (rc::DepthSensor) orbiting a procedural model or a mesh file, and broadcasts the
// sensor's pose with tf2 each frame.
//
// Publishes   points (sensor_msgs/PointCloud2 in frame_id: x y z [rgba], organised when simulated), /tf
//             (parent_frame -> frame_id, stamped like the cloud)
// Parameters  (private) files, model, model_resolution, ground_plane, mesh_file, rate, max_frames, frame_id,
//             parent_frame, width, height, horizontal_fov, min_range, max_range, noise_sigma_constant,
//             noise_sigma_quadratic, dropout_probability, seed, organized, publish_colors, orbit_radius,
//             orbit_height, orbit_angular_speed, orbit_start_angle, orbit_height_amplitude,
//             orbit_height_period, orbit_target; see config/scan.yaml.
#pragma once

#include <ros/ros.h>
#include <tf2_ros/transform_broadcaster.h>

#include <memory>
#include <string>
#include <vector>

#include "relaxed_connectivity/core/surfel_cloud.h"
#include "relaxed_connectivity/core/triangle_mesh.h"
#include "relaxed_connectivity/mesh/mesh_ray_caster.h"
#include "relaxed_connectivity/scan/depth_sensor.h"
#include "relaxed_connectivity/scan/sensor_trajectory.h"

namespace rc {

struct ScannerParams {
  std::vector<std::string>
      files;                   ///< non-empty: publish these clouds in turn (looping) instead of simulating
  std::string model = "blob";  ///< procedural model (rc::modelNames()) when neither files nor mesh_file
  int model_resolution = 16;
  bool ground_plane = false;
  std::string mesh_file;                     ///< mesh to scan instead of a procedural model
  double rate = 5.0;                         ///< frames per second
  int max_frames = 0;                        ///< stop (shut down) after this many frames; 0: run forever
  std::string frame_id = "scanner_optical";  ///< REP 103 optical frame (z forward, x right, y down)
  std::string parent_frame = "world";
  bool publish_colors = true;
  DepthSensorConfig sensor;  ///< intrinsics, range limits, noise, organised output
  OrbitParameters orbit;

  bool simulated() const { return files.empty(); }
  /// Throws std::invalid_argument naming the parameter and the bad value.
  void validate() const;
};

/// Reads the private parameters once (defaults: ScannerParams{} with a 160x120, 60 degree sensor) and
/// validates.
ScannerParams readScannerParams(const ros::NodeHandle& private_nh);

class ScannerNode {
 public:
  /// Reads and validates the parameters, loads the files or builds the scene (throws std::invalid_argument or
  /// rc::IoError with a clear message), advertises and starts the frame timer.
  ScannerNode(ros::NodeHandle nh, ros::NodeHandle private_nh);
  ~ScannerNode();

  /// Publishes one frame (the pose at `stamp`) and its transform. Returns the number of points published.
  size_t publishFrame(const ros::Time& stamp);
  const ScannerParams& params() const { return params_; }

 private:
  void onTimer(const ros::TimerEvent& event);

  ros::NodeHandle nh_, private_nh_;
  ScannerParams params_;
  ros::Publisher points_pub_;
  tf2_ros::TransformBroadcaster tf_broadcaster_;
  ros::Timer timer_;
  ros::WallTimer shutdown_timer_;
  ros::Time start_;
  uint64_t frame_index_ = 0;

  std::vector<SurfelCloud> file_clouds_;
  std::unique_ptr<TriangleMesh> mesh_;
  std::unique_ptr<MeshRayCaster> caster_;
  std::unique_ptr<DepthSensor> sensor_;
};

}  // namespace rc
