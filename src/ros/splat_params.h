// Parameters shared by the nodes that splat (csg_renderer, paint_renderer): the splatting options read from
// the node's private namespace, and the camera motion test that decides on a new (full) frame.
#pragma once

#include <ros/ros.h>

#include <Eigen/Geometry>
#include <string>

#include "relaxed_connectivity/render/splat/splat_config.h"

namespace rc {

/// Reads ewa_filter, lowpass_variance, cutoff_radius, depth_tolerance_scale, shading, backface_culling,
/// threads and background ([r, g, b], 0..255) into `splat` (its values are the defaults). Throws
/// std::invalid_argument "<node>: ..." for a bad background.
void readSplatParams(const ros::NodeHandle& private_nh, const std::string& node, SplatConfig* splat);

/// True if the poses differ by more than `tolerance` in translation [m] or rotation angle [rad].
bool cameraPoseMoved(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b, double tolerance);

}  // namespace rc
