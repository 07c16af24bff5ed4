// Parameters shared by the nodes that splat (csg_renderer, paint_renderer): the splatting options read from
// the node's private namespace, and the camera motion test that decides on a new (full) frame.
#pragma once

#include <ros/ros.h>

#include <Eigen/Geometry>
#include <string>

#include <relaxed_connectivity/SplatConfig.h>  // generated from config/dynamic_reconfigure/Splat.cfg
#include "relaxed_connectivity/render/splat/splat_config.h"

namespace rc {

/// Reads ewa_filter, lowpass_variance, cutoff_radius, depth_tolerance_scale, exact_footprint,
/// exact_silhouettes, shading, backface_culling, threads and background ([r, g, b], 0..255) into `splat` (its
/// values are the defaults). Throws std::invalid_argument "<node>: ..." for a bad background.
void readSplatParams(const ros::NodeHandle& private_nh, const std::string& node, SplatConfig* splat);

/// The dynamic_reconfigure splat settings (Splat.cfg) into `splat`; its other fields are kept.
void applySplatReconfigure(const relaxed_connectivity::SplatConfig& config, SplatConfig* splat);
/// The settings of `splat` into the reconfigure answer (the settings that stay after a refusal).
void writeSplatReconfigure(const SplatConfig& splat, relaxed_connectivity::SplatConfig* config);
/// True if the reconfigurable settings of `a` and `b` are equal.
bool sameSplatReconfigure(const SplatConfig& a, const SplatConfig& b);

/// True if the poses differ by more than `tolerance` in translation [m] or rotation angle [rad].
bool cameraPoseMoved(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b, double tolerance);

}  // namespace rc
