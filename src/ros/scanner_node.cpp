#include "relaxed_connectivity/ros/scanner_node.h"

#include <geometry_msgs/TransformStamped.h>
#include <tf2_eigen/tf2_eigen.h>

#include <cmath>
#include <stdexcept>

#include "relaxed_connectivity/io/cloud_io.h"
#include "relaxed_connectivity/ros/point_cloud2_converter.h"
#include "relaxed_connectivity/scan/procedural_models.h"

namespace rc {

namespace {
std::string shortFrame(const std::string& frame) {
  return !frame.empty() && frame[0] == '/' ? frame.substr(1) : frame;
}
}  // namespace

void ScannerParams::validate() const {
  auto fail = [](const std::string& what) { throw std::invalid_argument("scanner: " + what); };
  if (!(rate > 0) || !std::isfinite(rate))
    fail("rate must be a positive frequency in Hz (got " + std::to_string(rate) + ")");
  if (max_frames < 0) fail("max_frames must be >= 0 (got " + std::to_string(max_frames) + ")");
  if (frame_id.empty()) fail("frame_id must not be empty");
  if (parent_frame.empty()) fail("parent_frame must not be empty");
  if (frame_id == parent_frame) fail("frame_id and parent_frame must differ (both '" + frame_id + "')");
  for (const auto& f : files)
    if (f.empty()) fail("files contains an empty path");
  if (simulated()) {
    if (mesh_file.empty() && model.empty()) fail("set one of files, mesh_file or model");
    if (model_resolution < 1)
      fail("model_resolution must be >= 1 (got " + std::to_string(model_resolution) + ")");
    try {
      sensor.validate();
      validateOrbit(orbit);
    } catch (const std::invalid_argument& e) {
      fail(e.what());
    }
  }
}

ScannerParams readScannerParams(const ros::NodeHandle& pnh) {
  ScannerParams p;
  p.sensor.intrinsics = PinholeIntrinsics::fromHorizontalFov(160, 120, 60.0 * M_PI / 180.0);
  p.sensor.output_normals = false;  // a scanner measures positions (and colours) only
  pnh.param("files", p.files, p.files);
  pnh.param("model", p.model, p.model);
  pnh.param("model_resolution", p.model_resolution, p.model_resolution);
  pnh.param("ground_plane", p.ground_plane, p.ground_plane);
  pnh.param("mesh_file", p.mesh_file, p.mesh_file);
  pnh.param("rate", p.rate, p.rate);
  pnh.param("max_frames", p.max_frames, p.max_frames);
  pnh.param("frame_id", p.frame_id, p.frame_id);
  pnh.param("parent_frame", p.parent_frame, p.parent_frame);
  p.frame_id = shortFrame(p.frame_id);
  p.parent_frame = shortFrame(p.parent_frame);
  pnh.param("publish_colors", p.publish_colors, p.publish_colors);

  int width = 160, height = 120;
  double fov_deg = 60.0;
  pnh.param("width", width, width);
  pnh.param("height", height, height);
  pnh.param("horizontal_fov", fov_deg, fov_deg);
  if (width < 1 || height < 1)
    throw std::invalid_argument("scanner: width and height must be >= 1 (got " + std::to_string(width) +
                                " x " + std::to_string(height) + ")");
  if (!(fov_deg > 0 && fov_deg < 180))
    throw std::invalid_argument("scanner: horizontal_fov must be in (0, 180) degrees (got " +
                                std::to_string(fov_deg) + ")");
  p.sensor.intrinsics =
      PinholeIntrinsics::fromHorizontalFov(uint32_t(width), uint32_t(height), fov_deg * M_PI / 180);
  pnh.param("min_range", p.sensor.min_range, p.sensor.min_range);
  pnh.param("max_range", p.sensor.max_range, p.sensor.max_range);
  pnh.param("noise_sigma_constant", p.sensor.noise.sigma_constant, p.sensor.noise.sigma_constant);
  pnh.param("noise_sigma_quadratic", p.sensor.noise.sigma_quadratic, p.sensor.noise.sigma_quadratic);
  pnh.param("dropout_probability", p.sensor.noise.dropout_probability, p.sensor.noise.dropout_probability);
  int seed = 0;
  pnh.param("seed", seed, seed);
  p.sensor.seed = static_cast<uint64_t>(seed);
  pnh.param("organized", p.sensor.organized, p.sensor.organized);
  p.sensor.frame_id = p.frame_id;

  pnh.param("orbit_radius", p.orbit.radius, p.orbit.radius);
  pnh.param("orbit_height", p.orbit.height, p.orbit.height);
  pnh.param("orbit_angular_speed", p.orbit.angular_speed, p.orbit.angular_speed);
  pnh.param("orbit_start_angle", p.orbit.start_angle, p.orbit.start_angle);
  pnh.param("orbit_height_amplitude", p.orbit.height_amplitude, p.orbit.height_amplitude);
  pnh.param("orbit_height_period", p.orbit.height_period, p.orbit.height_period);
  std::vector<double> target = {p.orbit.target.x(), p.orbit.target.y(), p.orbit.target.z()};
  pnh.param("orbit_target", target, target);
  if (target.size() != 3)
    throw std::invalid_argument("scanner: orbit_target must be a list of 3 numbers (got " +
                                std::to_string(target.size()) + ")");
  p.orbit.target = Vec3(target[0], target[1], target[2]);
  p.validate();
  return p;
}

ScannerNode::ScannerNode(ros::NodeHandle nh, ros::NodeHandle private_nh)
    : nh_(nh), private_nh_(private_nh), params_(readScannerParams(private_nh)) {
  if (params_.simulated()) {
    if (!params_.mesh_file.empty()) {
      mesh_ = std::make_unique<TriangleMesh>(readMesh(params_.mesh_file));
      if (mesh_->triangles.empty())
        throw std::invalid_argument("scanner: mesh_file '" + params_.mesh_file + "' has no triangles");
    } else {
      mesh_ = std::make_unique<TriangleMesh>(
          makeModel(params_.model, params_.model_resolution, params_.ground_plane));
    }
    caster_ = std::make_unique<MeshRayCaster>(*mesh_);
    sensor_ = std::make_unique<DepthSensor>(params_.sensor);
    ROS_INFO_STREAM("scanner: simulating a "
                    << params_.sensor.intrinsics.width << "x" << params_.sensor.intrinsics.height
                    << " depth sensor on "
                    << (params_.mesh_file.empty() ? "model '" + params_.model + "'"
                                                  : "mesh '" + params_.mesh_file + "'")
                    << " (" << mesh_->triangles.size() << " triangles) at " << params_.rate << " Hz");
  } else {
    for (const auto& path : params_.files) {
      file_clouds_.push_back(readCloud(path));
      if (file_clouds_.back().empty()) ROS_WARN_STREAM("scanner: file '" << path << "' holds no points");
    }
    ROS_INFO_STREAM("scanner: publishing " << file_clouds_.size() << " file(s) in a loop at " << params_.rate
                                           << " Hz");
  }
  points_pub_ = nh_.advertise<sensor_msgs::PointCloud2>("points", 2);
  start_ = ros::Time::now();
  timer_ = nh_.createTimer(ros::Duration(1.0 / params_.rate), &ScannerNode::onTimer, this);
}

ScannerNode::~ScannerNode() = default;

size_t ScannerNode::publishFrame(const ros::Time& stamp) {
  SurfelCloud cloud;
  Eigen::Isometry3d world_T_sensor = Eigen::Isometry3d::Identity();
  if (params_.simulated()) {
    world_T_sensor = orbitTrajectory(params_.orbit, (stamp - start_).toSec());
    cloud = sensor_->capture(*caster_, world_T_sensor, frame_index_);
  } else {
    cloud = file_clouds_[frame_index_ % file_clouds_.size()];
  }
  if (!params_.publish_colors) cloud.colors.clear();
  cloud.frame_id = params_.frame_id;
  cloud.stamp_ns = stamp.toNSec();
  ++frame_index_;

  geometry_msgs::TransformStamped tf = tf2::eigenToTransform(world_T_sensor);
  tf.header.stamp = stamp;
  tf.header.frame_id = params_.parent_frame;
  tf.child_frame_id = params_.frame_id;
  tf_broadcaster_.sendTransform(tf);  // before the cloud, so listeners have it when the cloud arrives

  points_pub_.publish(PointCloud2Converter::toMessage(cloud, PointCloud2Layout::kCompact));
  return cloud.size();
}

void ScannerNode::onTimer(const ros::TimerEvent&) {
  try {
    publishFrame(ros::Time::now());
  } catch (const std::exception& e) {
    ROS_ERROR_STREAM("scanner: frame " << frame_index_ << " failed: " << e.what());
  }
  if (params_.max_frames > 0 && frame_index_ >= uint64_t(params_.max_frames)) {
    ROS_INFO_STREAM("scanner: published " << frame_index_ << " frames (max_frames), shutting down");
    timer_.stop();
    // Give subscribers a moment to receive the last frame before the node goes away.
    shutdown_timer_ = nh_.createWallTimer(
        ros::WallDuration(1.0), [](const ros::WallTimerEvent&) { ros::shutdown(); }, /*oneshot=*/true);
  }
}

}  // namespace rc
