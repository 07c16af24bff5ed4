// The surfel_estimator node/nodelet (like octomap_server: one class behind a node main and a nodelet): point
// clouds in, per-view and accumulated surfels out, in the fixed frame.
//
// Subscribes  points (sensor_msgs/PointCloud2, any frame with a tf2 path to fixed_frame)
// Publishes   surfels (PointCloud2, pcl::PointSurfel layout, fixed_frame), surfels_accumulated (latched),
//             ~stats (relaxed_connectivity/SurfelStats, one per input message, accepted or rejected),
//             /diagnostics (the input's rate, accepted and rejected messages, NodeDiagnostics)
// Services    ~reset_accumulation (relaxed_connectivity/ResetAccumulation),
//             ~save (relaxed_connectivity/SaveSurfels: accumulated surfels to .ply/.pcd/.xyz)
// Parameters  (private) fixed_frame, tf_queue_size, normal_k, radius_k, radius_scale, max_radius, min_points,
//             mls_smoothing, mls_support_radius, mls_fit, accumulation_voxel, max_accumulated_points,
//             accumulated_publish_period, save_path (written on shutdown); see config/scan.yaml.
#pragma once

#include <relaxed_connectivity/ResetAccumulation.h>
#include <relaxed_connectivity/SaveSurfels.h>
#include <relaxed_connectivity/SurfelStats.h>
#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/message_filter.h>
#include <tf2_ros/transform_listener.h>

#include <memory>
#include <mutex>
#include <string>

#include "relaxed_connectivity/ros/node_diagnostics.h"
#include "relaxed_connectivity/scan/surfel_accumulator.h"
#include "relaxed_connectivity/scan/surfel_estimation_pipeline.h"

namespace rc {

struct SurfelEstimatorParams {
  std::string fixed_frame = "world";
  /// Clouds waiting for the transform of their stamp (tf2_ros::MessageFilter); one pushed out of this queue
  /// by newer clouds, still without its transform, is rejected naming its frame.
  int tf_queue_size = 10;
  double accumulation_voxel = 0.005;        ///< metres; one accumulated surfel per voxel
  int max_accumulated_points = 1000000;     ///< cap of the accumulated cloud
  double accumulated_publish_period = 0.5;  ///< seconds between publications of the accumulated cloud
  std::string save_path;                    ///< if set, the accumulated surfels are written here on shutdown
  SurfelEstimationConfig estimation;

  /// Throws std::invalid_argument naming the parameter and the bad value.
  void validate() const;
};

/// Reads the private parameters once (defaults: SurfelEstimatorParams{}) and validates them.
SurfelEstimatorParams readSurfelEstimatorParams(const ros::NodeHandle& private_nh);

class SurfelEstimator {
 public:
  /// Reads and validates the parameters (throws std::invalid_argument), then subscribes and advertises.
  SurfelEstimator(ros::NodeHandle nh, ros::NodeHandle private_nh);
  /// Writes the accumulated surfels to save_path when it is set.
  ~SurfelEstimator();

  void cloudCallback(const sensor_msgs::PointCloud2ConstPtr& msg);
  bool resetAccumulation(relaxed_connectivity::ResetAccumulation::Request& request,
                         relaxed_connectivity::ResetAccumulation::Response& response);
  bool save(relaxed_connectivity::SaveSurfels::Request& request,
            relaxed_connectivity::SaveSurfels::Response& response);
  /// Writes the accumulated surfels to `path`; returns the count, throws rc::IoError on failure.
  size_t saveAccumulated(const std::string& path);

  const SurfelEstimatorParams& params() const { return params_; }

 private:
  void reject(const sensor_msgs::PointCloud2& msg, const std::string& reason, bool is_error,
              relaxed_connectivity::SurfelStats& stats);
  // A cloud as it comes: a malformed layout or no points is rejected at once, the others go to tf_filter_.
  void inputCallback(const sensor_msgs::PointCloud2ConstPtr& msg);
  // A cloud the message filter gave up on (empty frame, no transform in time): rejected with its reason.
  void transformFailed(const sensor_msgs::PointCloud2ConstPtr& msg,
                       tf2_ros::filter_failure_reasons::FilterFailureReason why);
  void publishAccumulated(const ros::WallTime& now);

  ros::NodeHandle nh_, private_nh_;
  SurfelEstimatorParams params_;
  tf2_ros::Buffer tf_buffer_;
  tf2_ros::TransformListener tf_listener_;
  std::string input_topic_;
  ros::Publisher surfels_pub_, accumulated_pub_, stats_pub_;
  ros::ServiceServer reset_srv_, save_srv_;
  NodeDiagnostics diagnostics_;

  std::mutex mutex_;  // guards everything below (nodelet managers call back from several threads)
  SurfelAccumulator accumulator_;
  uint32_t rejected_messages_ = 0;
  std::string last_error_;
  ros::WallTime last_accumulated_publish_;
  bool accumulated_dirty_ = false;

  // The input: checked clouds through a tf2_ros::MessageFilter to the fixed frame (last: stopped first).
  std::unique_ptr<tf2_ros::MessageFilter<sensor_msgs::PointCloud2>> tf_filter_;
  ros::Subscriber cloud_sub_;
};

}  // namespace rc
