#include "relaxed_connectivity/ros/paint_model.h"

#include <tf2_eigen/tf2_eigen.h>

#include <cmath>
#include <stdexcept>

#include "relaxed_connectivity/paint/brush_preset_reader.h"
#include "relaxed_connectivity/paint/paint_type_reader.h"
#include "relaxed_connectivity/ros/brush_messages.h"
#include "relaxed_connectivity/ros/point_cloud2_converter.h"

namespace rc {

void PaintModelParams::validate() const {
  auto fail = [](const std::string& what) { throw std::invalid_argument("paint_model: " + what); };
  if (brush.empty()) fail("the parameter ~brush (a brush preset file, config/paint/brushes/) is required");
  if (device.empty()) fail("device must not be empty");
  if (world_frame.empty() || world_frame[0] == '/')
    fail("world_frame '" + world_frame + "' is not a frame name");
  if (!(rate > 0) || !std::isfinite(rate)) fail("rate must be positive (got " + std::to_string(rate) + ")");
  try {
    brush_options.validate();
  } catch (const std::invalid_argument& e) {
    fail(e.what());
  }
  if (!(skin_rate >= 0) || !std::isfinite(skin_rate)) fail("skin_rate must be >= 0");
  if (!(painted_rate > 0) || !std::isfinite(painted_rate)) fail("painted_rate must be positive");
  if (drying_visits < 0) fail("drying_visits must be >= 0");
  try {
    transfer.validate();
  } catch (const std::invalid_argument& e) {
    fail(e.what());
  }
}

PaintModelParams readPaintModelParams(const ros::NodeHandle& pnh) {
  PaintModelParams p;
  pnh.param("brush", p.brush, p.brush);
  pnh.param("device", p.device, p.device);
  pnh.param("world_frame", p.world_frame, p.world_frame);
  pnh.param("rate", p.rate, p.rate);
  pnh.param("collision_passes", p.brush_options.collision_passes, p.brush_options.collision_passes);
  pnh.param("plane_proxy", p.brush_options.plane_proxy, p.brush_options.plane_proxy);
  pnh.param("proxy_reach", p.brush_options.proxy_reach, p.brush_options.proxy_reach);
  pnh.param("skin_rate", p.skin_rate, p.skin_rate);
  pnh.param("paint", p.paint, p.paint);
  pnh.param("pixel_size", p.transfer.pixel_size, p.transfer.pixel_size);
  pnh.param("pressure_per_depth", p.transfer.pressure_per_depth, p.transfer.pressure_per_depth);
  pnh.param("painted_rate", p.painted_rate, p.painted_rate);
  pnh.param("drying_visits", p.drying_visits, p.drying_visits);
  p.validate();
  return p;
}

PaintModel::PaintModel(ros::NodeHandle nh, ros::NodeHandle private_nh)
    : nh_(nh),
      private_nh_(private_nh),
      params_(readPaintModelParams(private_nh)),
      tf_listener_(tf_buffer_, nh) {
  brush_ = std::make_unique<Brush>(readBrushPreset(params_.brush), params_.brush_options);
  contact_pub_ = nh_.advertise<relaxed_connectivity::BrushContact>("brush_contact", 10);
  skeleton_pub_ = nh_.advertise<visualization_msgs::MarkerArray>("brush/skeleton", 2);
  skin_pub_ = nh_.advertise<sensor_msgs::PointCloud2>("brush/skin", 2);
  if (!params_.paint.empty()) {
    paint_type_ = std::make_unique<PaintType>(readPaintType(params_.paint));
    painted_pub_ = nh_.advertise<sensor_msgs::PointCloud2>("surfels/painted", 1, true);
    if (params_.drying_visits > 0 && paint_type_->drying_rate > 0)
      dryer_ = std::make_unique<PaintDryer>(paint_type_->drying_rate, paint_type_->drying);
  }
  start_ = ros::WallTime::now();
  surfels_sub_ = nh_.subscribe("surfels", 1, &PaintModel::surfelsCallback, this);
  pose_sub_ = nh_.subscribe(params_.device + "/pose", 10, &PaintModel::poseCallback, this,
                            ros::TransportHints().tcpNoDelay());
  timer_ = nh_.createWallTimer(ros::WallDuration(1.0 / params_.rate), &PaintModel::tick, this);
  ROS_INFO_STREAM("paint_model: brush '"
                  << brush_->preset().name << "' (" << brush_->skeleton().handleCount() << " handle points, "
                  << brush_->skeleton().activeCount() << " active masses, " << brush_->skin().size()
                  << " skin surfels), " << params_.rate << " Hz main loop, device poses on "
                  << pose_sub_.getTopic()
                  << (paint_type_ ? ", paint '" + paint_type_->name + "'" : ", no paint"));
}

void PaintModel::surfelsCallback(const sensor_msgs::PointCloud2ConstPtr& msg) {
  try {
    SurfelCloud cloud = PointCloud2Converter::fromMessage(*msg);
    const size_t dropped = cloud.removeNonFinite();
    if (!cloud.hasNormals()) throw std::invalid_argument("the cloud has no normals (normal_x/y/z)");
    if (msg->header.frame_id != params_.world_frame) {
      const auto tf = tf_buffer_.lookupTransform(params_.world_frame, msg->header.frame_id, ros::Time(0));
      cloud.transform(tf2::transformToEigen(tf));
    }
    cloud.frame_id = params_.world_frame;
    auto surface = std::make_shared<PaintSurface>(std::move(cloud));
    std::lock_guard<std::mutex> lock(mutex_);
    surface_ = surface;
    ROS_INFO_STREAM("paint_model: object of "
                    << surface_->originalCount() << " surfels"
                    << (dropped ? " (" + std::to_string(dropped) + " non-finite dropped)" : ""));
  } catch (const std::exception& e) {  // keep the current object
    ROS_ERROR_STREAM("paint_model: rejected surfels (frame '" << msg->header.frame_id << "', "
                                                              << msg->width * msg->height
                                                              << " points): " << e.what());
  }
}

void PaintModel::poseCallback(const geometry_msgs::PoseStampedConstPtr& msg) {
  const auto& p = msg->pose;
  const double q_norm = std::sqrt(p.orientation.x * p.orientation.x + p.orientation.y * p.orientation.y +
                                  p.orientation.z * p.orientation.z + p.orientation.w * p.orientation.w);
  if (!std::isfinite(p.position.x) || !std::isfinite(p.position.y) || !std::isfinite(p.position.z) ||
      !std::isfinite(q_norm) || std::abs(q_norm - 1) > 1e-3) {
    ROS_WARN_STREAM_THROTTLE(1.0,
                             "paint_model: dropped a device pose with a non-finite position or a non-unit "
                             "quaternion (|q| = "
                                 << q_norm << ")");
    return;
  }
  std::lock_guard<std::mutex> lock(mutex_);
  latest_pose_ = msg;
}

void PaintModel::tick(const ros::WallTimerEvent&) {
  geometry_msgs::PoseStampedConstPtr pose;
  std::shared_ptr<PaintSurface> surface;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    pose = latest_pose_;
    surface = surface_;
  }
  if (!pose) return;
  // The device pose in the world (a static tf world -> haptic_base in a session).
  Eigen::Isometry3d world_T_pose_frame = Eigen::Isometry3d::Identity();
  if (pose->header.frame_id != params_.world_frame) {
    try {
      world_T_pose_frame = tf2::transformToEigen(
          tf_buffer_.lookupTransform(params_.world_frame, pose->header.frame_id, ros::Time(0)));
    } catch (const tf2::TransformException& e) {
      ROS_WARN_STREAM_THROTTLE(2.0, "paint_model: no transform " << params_.world_frame << " -> "
                                                                 << pose->header.frame_id << ": "
                                                                 << e.what());
      return;
    }
  }
  Eigen::Isometry3d pose_frame_T_stylus;
  tf2::fromMsg(pose->pose, pose_frame_T_stylus);
  const Eigen::Isometry3d world_T_stylus = world_T_pose_frame * pose_frame_T_stylus;
  const double dt = 1.0 / params_.rate;
  try {
    if (!brush_placed_) {
      brush_->reset(world_T_stylus);
      brush_placed_ = true;
    }
    brush_->advance(dt, world_T_stylus, surface.get());
  } catch (const BrushInstability& e) {  // reported, then the brush restarts at rest at the device pose
    ++instabilities_;
    ROS_ERROR_STREAM("paint_model: " << e.what() << "; the brush restarts at rest (" << instabilities_
                                     << " so far)");
    brush_->reset(world_T_stylus);
  }
  if (paint_type_ && surface) {
    try {
      const PaintEventStats painted = transferPaint(*brush_, *surface, *paint_type_, dt, params_.transfer);
      painted_dirty_ = painted_dirty_ || painted.penetrated_pixels > 0;
      if (dryer_)  // (5.6.1) in bounded slices; what dries changes what is seen
        painted_dirty_ = dryer_->run(*surface, (ros::WallTime::now() - start_).toSec(),
                                     size_t(params_.drying_visits)) > 0 ||
                         painted_dirty_;
    } catch (const std::exception& e) {  // the event's paint is lost, the session goes on
      ROS_ERROR_STREAM_THROTTLE(1.0, "paint_model: paint transfer failed: " << e.what());
    }
  }
  contact_pub_.publish(toBrushContactMessage(*brush_, world_T_pose_frame.inverse(), pose->header.frame_id,
                                             pose->header.stamp));
  const ros::Time now = ros::Time::now();
  if (skeleton_pub_.getNumSubscribers() > 0)
    skeleton_pub_.publish(toSkeletonMarkers(*brush_, params_.world_frame, now));
  const ros::WallTime wall = ros::WallTime::now();
  if (params_.skin_rate > 0 && skin_pub_.getNumSubscribers() > 0 &&
      (wall - last_skin_).toSec() >= 1.0 / params_.skin_rate) {
    SurfelCloud skin = brush_->skin().cloud();
    skin.frame_id = params_.world_frame;
    skin.stamp_ns = now.toNSec();
    skin_pub_.publish(PointCloud2Converter::toMessage(skin));
    last_skin_ = wall;
  }
  if (painted_dirty_ && surface && (wall - last_painted_).toSec() >= 1.0 / params_.painted_rate) {
    SurfelCloud painted = surface->activeCloud();
    painted.frame_id = params_.world_frame;
    painted.stamp_ns = now.toNSec();
    painted_pub_.publish(PointCloud2Converter::toMessage(painted));
    painted_dirty_ = false;
    last_painted_ = wall;
  }
}

}  // namespace rc
