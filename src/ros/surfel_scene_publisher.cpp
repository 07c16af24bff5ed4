#include "relaxed_connectivity/ros/surfel_scene_publisher.h"

#include <relaxed_connectivity/SetCsgTree.h>
#include <tf2_eigen/tf2_eigen.h>

#include <cmath>
#include <stdexcept>

#include "relaxed_connectivity/ros/point_cloud2_converter.h"

namespace rc {
namespace {

void appendExpression(const CsgTree& tree, int node, bool top, std::string& out) {
  const CsgTree::Node& n = tree.node(node);
  switch (n.op) {
    case CsgTree::Op::kLeaf:
      out += (n.inverted ? "!" : "") + std::to_string(n.patch);
      return;
    case CsgTree::Op::kComplement:
      out += "!(";
      appendExpression(tree, n.left, true, out);
      out += ")";
      return;
    default: {
      const char* op = n.op == CsgTree::Op::kUnion          ? " | "
                       : n.op == CsgTree::Op::kIntersection ? " & "
                                                            : " - ";
      if (!top) out += "(";
      appendExpression(tree, n.left, false, out);
      out += op;
      appendExpression(tree, n.right, false, out);
      if (!top) out += ")";
    }
  }
}

}  // namespace

std::string patchIdExpression(const CsgTree& tree) {
  std::string out;
  if (!tree.empty()) appendExpression(tree, tree.root(), true, out);
  return out;
}

void SurfelScenePublisherParams::validate() const {
  auto fail = [](const std::string& what) { throw std::invalid_argument("surfel_scene_publisher: " + what); };
  if (scene.empty()) fail("parameter ~scene (a scene file, see config/scenes/) is required");
  if (frame_id.empty() || frame_id[0] == '/')
    fail("frame_id '" + frame_id + "' must be non-empty without '/'");
  if (!(rate > 0) || !std::isfinite(rate)) fail("rate must be > 0 Hz (got " + std::to_string(rate) + ")");
  if (!std::isfinite(time_scale)) fail("time_scale must be finite");
  if (!std::isfinite(camera_orbit_speed)) fail("camera_orbit_speed must be finite");
  if (!camera_frame.empty() && camera_frame[0] == '/') fail("camera_frame must not start with '/'");
}

SurfelScenePublisherParams readSurfelScenePublisherParams(const ros::NodeHandle& pnh) {
  SurfelScenePublisherParams p;
  pnh.param("scene", p.scene, p.scene);
  pnh.param("frame_id", p.frame_id, p.frame_id);
  pnh.param("rate", p.rate, p.rate);
  pnh.param("time_scale", p.time_scale, p.time_scale);
  pnh.param("csg_service", p.csg_service, p.csg_service);
  pnh.param("camera_frame", p.camera_frame, p.camera_frame);
  pnh.param("camera", p.camera, p.camera);
  pnh.param("camera_orbit_speed", p.camera_orbit_speed, p.camera_orbit_speed);
  p.validate();
  return p;
}

SurfelScenePublisher::SurfelScenePublisher(ros::NodeHandle nh, ros::NodeHandle private_nh)
    : nh_(nh), private_nh_(private_nh), params_(readSurfelScenePublisherParams(private_nh)) {
  scene_ = loadCsgScene(params_.scene);
  expression_ = patchIdExpression(scene_.csgTree());
  moving_ = scene_.surfels;
  moving_.frame_id = params_.frame_id;
  if (!params_.camera_frame.empty()) {
    const CsgSceneCamera* chosen = nullptr;
    for (const CsgSceneCamera& c : scene_.cameras)
      if (params_.camera.empty() ? chosen == nullptr : c.name == params_.camera) chosen = &c;
    if (!params_.camera.empty() && !chosen)
      throw std::invalid_argument("surfel_scene_publisher: scene '" + scene_.name + "' has no camera '" +
                                  params_.camera + "'");
    if (chosen) {
      camera_ = chosen->camera;
    } else {  // scenes without cameras: look at the origin from the front, above
      camera_.lookAt(Vec3(3, -4, 2), Vec3::Zero());
    }
  }
  surfels_pub_ = nh_.advertise<sensor_msgs::PointCloud2>("surfels", 1, /*latch=*/true);
  start_ = ros::WallTime::now();
  publishFrame(0.0);
  timer_ =
      nh_.createWallTimer(ros::WallDuration(1.0 / params_.rate), &SurfelScenePublisher::timerCallback, this);
  ROS_INFO_STREAM("surfel_scene_publisher: scene '"
                  << scene_.name << "' (" << scene_.surfels.size() << " surfels, " << scene_.patches.size()
                  << " patches, " << (scene_.isDynamic() ? "dynamic" : "static") << "), csg \""
                  << scene_.geometry_expression << "\" = \"" << expression_ << "\"");
}

void SurfelScenePublisher::publishFrame(double t) {
  const bool first = t == 0.0;
  if (first || scene_.isDynamic()) {
    if (!first) scene_.moveTo(t, &moving_);
    sensor_msgs::PointCloud2Ptr msg = PointCloud2Converter::toMessage(moving_);
    msg->header.frame_id = params_.frame_id;
    msg->header.stamp = ros::Time::now();
    surfels_pub_.publish(msg);  // never modified after publishing
  }
  if (params_.camera_frame.empty() || (!first && params_.camera_orbit_speed == 0.0)) return;
  // The camera orbits the z axis of frame_id (scenes are centred at the origin).
  const Eigen::Isometry3d orbit(
      Eigen::AngleAxisd(params_.camera_orbit_speed * M_PI / 180.0 * t, Vec3::UnitZ()));
  const Eigen::Isometry3d pose = orbit * camera_.world_T_camera;
  geometry_msgs::TransformStamped tf = tf2::eigenToTransform(pose);
  tf.header.frame_id = params_.frame_id;
  tf.header.stamp = ros::Time::now();
  tf.child_frame_id = params_.camera_frame;
  if (params_.camera_orbit_speed == 0.0)
    static_tf_.sendTransform(tf);
  else
    tf_.sendTransform(tf);
}

void SurfelScenePublisher::sendExpression() {
  if (expression_sent_ || params_.csg_service.empty() || expression_.empty()) return;
  if (!ros::service::exists(params_.csg_service, false)) return;  // retried next frame
  relaxed_connectivity::SetCsgTree srv;
  srv.request.expression = expression_;
  if (!ros::service::call(params_.csg_service, srv)) return;
  expression_sent_ = true;
  if (srv.response.success)
    ROS_INFO_STREAM("surfel_scene_publisher: sent csg \"" << expression_ << "\" to " << params_.csg_service);
  else
    ROS_ERROR_STREAM("surfel_scene_publisher: " << params_.csg_service << " rejected \"" << expression_
                                                << "\": " << srv.response.message);
}

void SurfelScenePublisher::timerCallback(const ros::WallTimerEvent&) {
  try {
    sendExpression();
    publishFrame(params_.time_scale * (ros::WallTime::now() - start_).toSec());
  } catch (const std::exception& e) {
    ROS_ERROR_STREAM_THROTTLE(5.0, "surfel_scene_publisher: " << e.what());
  }
}

}  // namespace rc
