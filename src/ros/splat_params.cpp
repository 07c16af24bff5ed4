#include "relaxed_connectivity/ros/splat_params.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

namespace rc {

void readSplatParams(const ros::NodeHandle& pnh, const std::string& node, SplatConfig* splat) {
  SplatConfig& s = *splat;
  pnh.param("ewa_filter", s.ewa_filter, s.ewa_filter);
  pnh.param("lowpass_variance", s.lowpass_variance, s.lowpass_variance);
  pnh.param("cutoff_radius", s.cutoff_radius, s.cutoff_radius);
  pnh.param("depth_tolerance_scale", s.depth_tolerance_scale, s.depth_tolerance_scale);
  pnh.param("shading", s.shading, s.shading);
  pnh.param("backface_culling", s.backface_culling, s.backface_culling);
  pnh.param("exact_footprint", s.exact_footprint, s.exact_footprint);
  pnh.param("threads", s.threads, s.threads);
  std::vector<int> background{s.background[0], s.background[1], s.background[2]};
  pnh.param("background", background, background);
  if (background.size() != 3 || *std::min_element(background.begin(), background.end()) < 0 ||
      *std::max_element(background.begin(), background.end()) > 255)
    throw std::invalid_argument(node + ": background must be [r, g, b] with values in 0..255");
  s.background = {uint8_t(background[0]), uint8_t(background[1]), uint8_t(background[2]), 255};
}

bool cameraPoseMoved(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b, double tolerance) {
  const double translation = (a.translation() - b.translation()).norm();
  const double angle = Eigen::AngleAxisd(a.linear().transpose() * b.linear()).angle();
  return !(translation <= tolerance && std::abs(angle) <= tolerance);
}

}  // namespace rc
