#include "relaxed_connectivity/ros/marker_haptic_device.h"

#include <visualization_msgs/InteractiveMarker.h>

#include "relaxed_connectivity/ros/six_dof_marker.h"

namespace rc {

MarkerHapticDevice::MarkerHapticDevice(const std::string& topic_ns, const std::string& frame,
                                       const Vec3& start_position, double brush_length) {
  server_ =
      std::make_unique<interactive_markers::InteractiveMarkerServer>(topic_ns, "", /*spin_thread=*/false);
  visualization_msgs::InteractiveMarker marker;
  marker.header.frame_id = frame;
  marker.name = "stylus";
  marker.description = "haptic stylus (right click: paint)";
  marker.scale = float(3 * brush_length);
  marker.pose.position.x = start_position.x();
  marker.pose.position.y = start_position.y();
  marker.pose.position.z = start_position.z();
  marker.pose.orientation.w = 1;
  // The stylus: a cylinder from the ferrule (origin) along -z, the bristles' direction.
  visualization_msgs::Marker body;
  body.type = visualization_msgs::Marker::CYLINDER;
  body.scale.x = body.scale.y = 0.25 * brush_length;
  body.scale.z = brush_length;
  body.pose.position.z = -0.5 * brush_length;
  body.pose.orientation.w = 1;
  body.color = markerColor(0.8f, 0.6f, 0.2f);
  addSixDofControls(body, &marker);
  server_->insert(marker, [this](const auto& f) { feedback(f); });
  paint_entry_ = menu_.insert("Paint (button 0)", [this](const auto& f) { togglePaint(f); });
  menu_.setCheckState(paint_entry_, interactive_markers::MenuHandler::UNCHECKED);
  menu_.apply(*server_, marker.name);
  server_->applyChanges();
  setPose(0.0, start_position, Eigen::Quaterniond::Identity());
}

void MarkerHapticDevice::feedback(const visualization_msgs::InteractiveMarkerFeedbackConstPtr& f) {
  if (f->event_type != visualization_msgs::InteractiveMarkerFeedback::POSE_UPDATE) return;
  const auto& p = f->pose.position;
  const auto& q = f->pose.orientation;
  const Vec3 position(p.x, p.y, p.z);
  const Eigen::Quaterniond orientation(q.w, q.x, q.y, q.z);
  if (checkDevicePose(position, orientation) != PoseProblem::kNone) return;
  // Seconds since the first feedback (epoch seconds in a double resolve only ~240 ns).
  const ros::Time stamp = f->header.stamp.isZero() ? ros::Time::now() : f->header.stamp;
  if (stamp_origin_.isZero()) stamp_origin_ = stamp;
  setPose((stamp - stamp_origin_).toSec(), position, orientation);
}

void MarkerHapticDevice::togglePaint(const visualization_msgs::InteractiveMarkerFeedbackConstPtr& f) {
  painting_ = !painting_;
  menu_.setCheckState(paint_entry_, painting_ ? interactive_markers::MenuHandler::CHECKED
                                              : interactive_markers::MenuHandler::UNCHECKED);
  menu_.reApply(*server_);
  server_->applyChanges();
  setButtons(painting_ ? 1u : 0u);
}

}  // namespace rc
