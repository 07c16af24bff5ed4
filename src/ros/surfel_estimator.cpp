#include "relaxed_connectivity/ros/surfel_estimator.h"

#include "relaxed_connectivity/io/cloud_io.h"

#include <tf2_eigen/tf2_eigen.h>

#include <cmath>
#include <stdexcept>

#include "relaxed_connectivity/ros/point_cloud2_converter.h"

namespace rc {

void SurfelEstimatorParams::validate() const {
  auto fail = [](const std::string& what) { throw std::invalid_argument("surfel_estimator: " + what); };
  if (fixed_frame.empty()) fail("fixed_frame must not be empty");
  if (!fixed_frame.empty() && fixed_frame[0] == '/')
    fail("fixed_frame '" + fixed_frame + "' must not start with '/'");
  if (tf_queue_size < 1) fail("tf_queue_size must be >= 1 (got " + std::to_string(tf_queue_size) + ")");
  if (!(accumulation_voxel > 0) || !std::isfinite(accumulation_voxel))
    fail("accumulation_voxel must be a positive length (got " + std::to_string(accumulation_voxel) + ")");
  if (max_accumulated_points < 1)
    fail("max_accumulated_points must be >= 1 (got " + std::to_string(max_accumulated_points) + ")");
  if (!(accumulated_publish_period >= 0) || !std::isfinite(accumulated_publish_period))
    fail("accumulated_publish_period must be >= 0 seconds (got " +
         std::to_string(accumulated_publish_period) + ")");
  estimation.validate();
}

SurfelEstimatorParams readSurfelEstimatorParams(const ros::NodeHandle& pnh) {
  SurfelEstimatorParams p;
  pnh.param("fixed_frame", p.fixed_frame, p.fixed_frame);
  pnh.param("tf_queue_size", p.tf_queue_size, p.tf_queue_size);
  pnh.param("accumulation_voxel", p.accumulation_voxel, p.accumulation_voxel);
  pnh.param("max_accumulated_points", p.max_accumulated_points, p.max_accumulated_points);
  pnh.param("accumulated_publish_period", p.accumulated_publish_period, p.accumulated_publish_period);
  pnh.param("save_path", p.save_path, p.save_path);
  SurfelEstimationConfig& e = p.estimation;
  pnh.param("normal_k", e.normals.k, e.normals.k);
  pnh.param("radius_k", e.radii.k, e.radii.k);
  pnh.param("radius_scale", e.radii.scale, e.radii.scale);
  pnh.param("max_radius", e.radii.max_radius, e.radii.max_radius);
  int min_points = static_cast<int>(e.min_points);
  pnh.param("min_points", min_points, min_points);
  if (min_points < 0) throw std::invalid_argument("surfel_estimator: min_points must be >= 3");
  e.min_points = static_cast<size_t>(min_points);
  pnh.param("mls_smoothing", e.mls_smoothing, e.mls_smoothing);
  double support = 0.05;
  pnh.param("mls_support_radius", support, support);
  e.mls.weight = WeightFunction::wendland(support);
  std::string fit = mlsFitName(e.mls.fit);
  pnh.param("mls_fit", fit, fit);
  e.mls.fit = parseMlsFit(fit);
  pnh.param("mls_max_iterations", e.mls.max_iterations, e.mls.max_iterations);
  p.validate();
  return p;
}

SurfelEstimator::SurfelEstimator(ros::NodeHandle nh, ros::NodeHandle private_nh)
    : nh_(nh),
      private_nh_(private_nh),
      params_(readSurfelEstimatorParams(private_nh)),
      tf_listener_(tf_buffer_, nh),
      diagnostics_(nh, private_nh, "surfel_estimator"),
      accumulator_(params_.accumulation_voxel, static_cast<size_t>(params_.max_accumulated_points)) {
  surfels_pub_ = nh_.advertise<sensor_msgs::PointCloud2>("surfels", 2);
  accumulated_pub_ = nh_.advertise<sensor_msgs::PointCloud2>("surfels_accumulated", 1, /*latch=*/true);
  stats_pub_ = private_nh_.advertise<relaxed_connectivity::SurfelStats>("stats", 10);
  reset_srv_ = private_nh_.advertiseService("reset_accumulation", &SurfelEstimator::resetAccumulation, this);
  save_srv_ = private_nh_.advertiseService("save", &SurfelEstimator::save, this);
  // Malformed clouds are rejected at once (inputCallback); the others wait for the transform of their stamp
  // in a tf2_ros::MessageFilter (no lookup blocks a callback).
  tf_filter_ = std::make_unique<tf2_ros::MessageFilter<sensor_msgs::PointCloud2>>(
      tf_buffer_, params_.fixed_frame, uint32_t(params_.tf_queue_size), nh_);
  cloud_sub_ = nh_.subscribe("points", 10, &SurfelEstimator::inputCallback, this);
  tf_filter_->registerCallback(&SurfelEstimator::cloudCallback, this);
  tf_filter_->registerFailureCallback(
      [this](const sensor_msgs::PointCloud2ConstPtr& msg,
             tf2_ros::filter_failure_reasons::FilterFailureReason why) { transformFailed(msg, why); });
  input_topic_ = cloud_sub_.getTopic();
  diagnostics_.addInput(input_topic_, 5.0);
  ROS_INFO_STREAM("surfel_estimator: listening on " << input_topic_ << ", fixed frame '"
                                                    << params_.fixed_frame << "', accumulation voxel "
                                                    << params_.accumulation_voxel << " m, MLS smoothing "
                                                    << (params_.estimation.mls_smoothing ? "on" : "off"));
}

void SurfelEstimator::reject(const sensor_msgs::PointCloud2& msg, const std::string& reason, bool is_error,
                             relaxed_connectivity::SurfelStats& stats) {
  const std::string text = "rejected cloud (frame '" + msg.header.frame_id + "', stamp " +
                           std::to_string(msg.header.stamp.toSec()) + "): " + reason;
  if (is_error)
    ROS_ERROR_STREAM("surfel_estimator: " << text);
  else
    ROS_WARN_STREAM("surfel_estimator: " << text);
  ++rejected_messages_;
  last_error_ = text;
  diagnostics_.rejected(input_topic_, reason);
  stats.output_surfels = 0;
}

void SurfelEstimator::inputCallback(const sensor_msgs::PointCloud2ConstPtr& msg) {
  std::string problem;
  try {
    PointCloud2Converter::checkMessage(*msg);  // the layout, without touching the points
    if (msg->width == 0 || msg->height == 0) problem = "empty cloud (0 points)";
  } catch (const std::exception& e) {
    problem = e.what();
  }
  if (problem.empty()) {
    tf_filter_->add(msg);
    return;
  }
  relaxed_connectivity::SurfelStats stats;
  stats.header = msg->header;
  stats.input_points = msg->width * msg->height;
  std::lock_guard<std::mutex> lock(mutex_);
  reject(*msg, problem, problem.rfind("empty cloud", 0) != 0, stats);
  stats.accumulated_surfels = static_cast<uint32_t>(accumulator_.size());
  stats.rejected_messages = rejected_messages_;
  stats.last_error = last_error_;
  stats_pub_.publish(stats);
}

void SurfelEstimator::transformFailed(const sensor_msgs::PointCloud2ConstPtr& msg,
                                      tf2_ros::filter_failure_reasons::FilterFailureReason why) {
  std::string reason;
  switch (why) {
    case tf2_ros::filter_failure_reasons::EmptyFrameID:
      reason = "header.frame_id is empty";
      break;
    case tf2_ros::filter_failure_reasons::OutTheBack:
      reason = "no transform from '" + msg->header.frame_id + "' to '" + params_.fixed_frame +
               "': the stamp is older than the transforms kept";
      break;
    default:
      reason = "no transform from '" + msg->header.frame_id + "' to '" + params_.fixed_frame + "' while " +
               std::to_string(params_.tf_queue_size) + " newer clouds arrived (tf2_ros::MessageFilter queue)";
  }
  relaxed_connectivity::SurfelStats stats;
  stats.header = msg->header;
  stats.input_points = msg->width * msg->height;
  std::lock_guard<std::mutex> lock(mutex_);
  reject(*msg, reason, true, stats);
  stats.accumulated_surfels = static_cast<uint32_t>(accumulator_.size());
  stats.rejected_messages = rejected_messages_;
  stats.last_error = last_error_;
  stats_pub_.publish(stats);
}

void SurfelEstimator::cloudCallback(const sensor_msgs::PointCloud2ConstPtr& msg) {
  const ros::WallTime start = ros::WallTime::now();
  relaxed_connectivity::SurfelStats stats;
  stats.header = msg->header;
  stats.input_points = msg->width * msg->height;

  std::lock_guard<std::mutex> lock(mutex_);
  try {
    SurfelCloud view;
    try {
      PointCloud2Converter::fromMessage(*msg, view);
    } catch (const PointCloud2Error& e) {
      throw std::runtime_error(e.what());
    }
    if (view.empty()) throw std::invalid_argument("empty cloud (0 points)");
    // Cheap data checks before waiting for tf.
    size_t finite = 0;
    for (const auto& p : view.positions) finite += p.allFinite();
    stats.valid_points = static_cast<uint32_t>(finite);
    if (finite == 0)
      throw std::invalid_argument("no finite points (all " + std::to_string(view.size()) + " are NaN/Inf)");
    if (msg->header.frame_id.empty()) throw std::runtime_error("header.frame_id is empty");

    Eigen::Isometry3d sensor_to_fixed;
    try {
      // (the message filter has seen it transformable)
      const auto tf =
          tf_buffer_.lookupTransform(params_.fixed_frame, msg->header.frame_id, msg->header.stamp);
      sensor_to_fixed = tf2::transformToEigen(tf);
    } catch (const tf2::TransformException& e) {
      throw std::runtime_error("no transform from '" + msg->header.frame_id + "' to '" + params_.fixed_frame +
                               "': " + e.what());
    }

    SurfelEstimationStats s;
    SurfelCloud surfels =
        estimateSurfels(std::move(view), sensor_to_fixed, params_.fixed_frame, params_.estimation, &s);
    stats.valid_points = static_cast<uint32_t>(s.valid_points);
    stats.output_surfels = static_cast<uint32_t>(s.output_surfels);

    sensor_msgs::PointCloud2Ptr out = PointCloud2Converter::toMessage(surfels);
    out->header.stamp = msg->header.stamp;
    surfels_pub_.publish(out);  // never modified after publishing (nodelet zero-copy)

    accumulated_dirty_ = accumulator_.add(surfels) > 0 || accumulated_dirty_;
    publishAccumulated(ros::WallTime::now());
    diagnostics_.accepted(input_topic_);
  } catch (const std::invalid_argument& e) {  // data problems: empty, NaN-only, too few points
    reject(*msg, e.what(), false, stats);
  } catch (const std::exception& e) {  // malformed message, unknown frame, core failures
    reject(*msg, e.what(), true, stats);
  }
  stats.accumulated_surfels = static_cast<uint32_t>(accumulator_.size());
  stats.rejected_messages = rejected_messages_;
  stats.last_error = last_error_;
  stats.processing_time = (ros::WallTime::now() - start).toSec();
  stats_pub_.publish(stats);
}

void SurfelEstimator::publishAccumulated(const ros::WallTime& now) {
  if (!accumulated_dirty_) return;
  if (!last_accumulated_publish_.isZero() &&
      (now - last_accumulated_publish_).toSec() < params_.accumulated_publish_period)
    return;
  sensor_msgs::PointCloud2Ptr msg = PointCloud2Converter::toMessage(accumulator_.cloud());
  msg->header.frame_id = params_.fixed_frame;
  accumulated_pub_.publish(msg);
  last_accumulated_publish_ = now;
  accumulated_dirty_ = false;
}

bool SurfelEstimator::resetAccumulation(relaxed_connectivity::ResetAccumulation::Request&,
                                        relaxed_connectivity::ResetAccumulation::Response& response) {
  std::lock_guard<std::mutex> lock(mutex_);
  response.dropped_surfels = static_cast<uint32_t>(accumulator_.reset());
  response.success = true;
  response.message = "dropped " + std::to_string(response.dropped_surfels) + " surfels";
  ROS_INFO_STREAM("surfel_estimator: accumulation reset, dropped " << response.dropped_surfels << " surfels");
  SurfelCloud empty;
  sensor_msgs::PointCloud2Ptr msg = PointCloud2Converter::toMessage(empty);
  msg->header.frame_id = params_.fixed_frame;
  msg->header.stamp = ros::Time::now();
  accumulated_pub_.publish(msg);
  last_accumulated_publish_ = ros::WallTime::now();
  accumulated_dirty_ = false;
  return true;
}

SurfelEstimator::~SurfelEstimator() {
  if (params_.save_path.empty()) return;
  try {
    const size_t n = saveAccumulated(params_.save_path);
    ROS_INFO_STREAM("surfel_estimator: wrote " << n << " accumulated surfels to " << params_.save_path);
  } catch (const std::exception& e) {
    ROS_ERROR_STREAM("surfel_estimator: could not save the accumulated surfels: " << e.what());
  }
}

size_t SurfelEstimator::saveAccumulated(const std::string& path) {
  std::lock_guard<std::mutex> lock(mutex_);
  SurfelCloud cloud = accumulator_.cloud();
  cloud.frame_id = params_.fixed_frame;
  writeCloud(path, cloud);
  return cloud.size();
}

bool SurfelEstimator::save(relaxed_connectivity::SaveSurfels::Request& request,
                           relaxed_connectivity::SaveSurfels::Response& response) {
  try {
    response.saved_surfels = static_cast<uint32_t>(saveAccumulated(request.path));
    response.success = true;
    response.message = "saved " + std::to_string(response.saved_surfels) + " surfels to " + request.path;
    ROS_INFO_STREAM("surfel_estimator: " << response.message);
  } catch (const std::exception& e) {
    response.success = false;
    response.message = e.what();
    ROS_ERROR_STREAM("surfel_estimator: save failed: " << e.what());
  }
  return true;
}

}  // namespace rc
