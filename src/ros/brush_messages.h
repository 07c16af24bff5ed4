// Messages of the brush (like grid_map's converter: one place that turns core brush state into ROS messages):
// the contact parameters for the haptic force loop, the skeleton as rviz markers, the skin as a PointCloud2.
#pragma once

#include <relaxed_connectivity/BrushContact.h>
#include <visualization_msgs/MarkerArray.h>

#include <Eigen/Geometry>
#include <string>

#include "relaxed_connectivity/paint/brush.h"

namespace rc {

/// The contact parameters of the brush's handle points (5.4.2) expressed in `frame` (the device's pose
/// frame): `frame_T_world` maps the brush's world-frame positions and normals into it.
relaxed_connectivity::BrushContact toBrushContactMessage(const Brush& brush,
                                                         const Eigen::Isometry3d& frame_T_world,
                                                         const std::string& frame, const ros::Time& stamp);

/// The skeleton in `frame` (the brush's world frame): handle points as blue spheres, active masses red (dark
/// red when colliding), springs as grey lines; namespace "brush_skeleton", ids 0..2.
visualization_msgs::MarkerArray toSkeletonMarkers(const Brush& brush, const std::string& frame,
                                                  const ros::Time& stamp);

}  // namespace rc
