#include "relaxed_connectivity/ros/brush_messages.h"

#include <tf2_eigen/tf2_eigen.h>

namespace rc {

relaxed_connectivity::BrushContact toBrushContactMessage(const Brush& brush,
                                                         const Eigen::Isometry3d& frame_T_world,
                                                         const std::string& frame, const ros::Time& stamp) {
  relaxed_connectivity::BrushContact msg;
  msg.header.frame_id = frame;
  msg.header.stamp = stamp;
  msg.penalty_stiffness = brush.preset().penalty_stiffness;
  msg.friction = brush.preset().friction;
  for (const HandlePointContact& c : brush.handleContacts()) {
    relaxed_connectivity::HandleContact h;
    h.index = uint32_t(c.index);
    h.depth = c.depth;
    tf2::toMsg(Vec3(frame_T_world.linear() * c.normal), h.normal);
    h.position = tf2::toMsg(Vec3(frame_T_world * c.position));
    msg.handles.push_back(h);
  }
  tf2::toMsg(Vec3(frame_T_world.linear() * brush.skeleton().bristleForce()), msg.bristle_force);
  return msg;
}

visualization_msgs::MarkerArray toSkeletonMarkers(const Brush& brush, const std::string& frame,
                                                  const ros::Time& stamp) {
  const BrushSkeleton& s = brush.skeleton();
  const double size = 0.15 * brush.preset().radius + 0.0005;
  visualization_msgs::MarkerArray out;
  auto marker = [&](int id, int type) {
    visualization_msgs::Marker m;
    m.header.frame_id = frame;
    m.header.stamp = stamp;
    m.ns = "brush_skeleton";
    m.id = id;
    m.type = type;
    m.action = visualization_msgs::Marker::ADD;
    m.pose.orientation.w = 1;
    m.scale.x = m.scale.y = m.scale.z = size;
    m.color.a = 1;
    return m;
  };
  visualization_msgs::Marker handles = marker(0, visualization_msgs::Marker::SPHERE_LIST);
  handles.color.b = 1;
  visualization_msgs::Marker actives = marker(1, visualization_msgs::Marker::SPHERE_LIST);
  actives.color.r = 1;
  visualization_msgs::Marker springs = marker(2, visualization_msgs::Marker::LINE_LIST);
  springs.scale.x = 0.2 * size;
  springs.color.r = springs.color.g = springs.color.b = 0.6f;
  for (int i = 0; i < s.nodeCount(); ++i) {
    const geometry_msgs::Point p = tf2::toMsg(s.positions()[i]);
    if (s.isHandle(i)) {
      handles.points.push_back(p);
    } else {
      actives.points.push_back(p);
      std_msgs::ColorRGBA c;
      c.a = 1;
      c.r = brush.activeContacts()[i - s.handleCount()].inside ? 0.5f : 1.0f;
      actives.colors.push_back(c);
    }
  }
  for (const BrushSpring& spring : s.springs()) {
    springs.points.push_back(tf2::toMsg(s.positions()[spring.a]));
    springs.points.push_back(tf2::toMsg(s.positions()[spring.b]));
  }
  out.markers = {handles, actives, springs};
  return out;
}

}  // namespace rc
