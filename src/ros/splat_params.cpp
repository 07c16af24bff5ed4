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
  pnh.param("exact_silhouettes", s.exact_silhouettes, s.exact_silhouettes);
  pnh.param("threads", s.threads, s.threads);
  std::vector<int> background{s.background[0], s.background[1], s.background[2]};
  pnh.param("background", background, background);
  if (background.size() != 3 || *std::min_element(background.begin(), background.end()) < 0 ||
      *std::max_element(background.begin(), background.end()) > 255)
    throw std::invalid_argument(node + ": background must be [r, g, b] with values in 0..255");
  s.background = {uint8_t(background[0]), uint8_t(background[1]), uint8_t(background[2]), 255};
}

void applySplatReconfigure(const relaxed_connectivity::SplatConfig& config, SplatConfig* splat) {
  splat->ewa_filter = config.ewa_filter;
  splat->lowpass_variance = config.lowpass_variance;
  splat->cutoff_radius = config.cutoff_radius;
  splat->depth_tolerance_scale = config.depth_tolerance_scale;
  splat->exact_footprint = config.exact_footprint;
  splat->exact_silhouettes = config.exact_silhouettes;
  splat->backface_culling = config.backface_culling;
  splat->shading = config.shading;
  splat->ambient = config.ambient;
  splat->diffuse = config.diffuse;
  splat->specular = config.specular;
  splat->shininess = config.shininess;
}

void writeSplatReconfigure(const SplatConfig& splat, relaxed_connectivity::SplatConfig* config) {
  config->ewa_filter = splat.ewa_filter;
  config->lowpass_variance = splat.lowpass_variance;
  config->cutoff_radius = splat.cutoff_radius;
  config->depth_tolerance_scale = splat.depth_tolerance_scale;
  config->exact_footprint = splat.exact_footprint;
  config->exact_silhouettes = splat.exact_silhouettes;
  config->backface_culling = splat.backface_culling;
  config->shading = splat.shading;
  config->ambient = splat.ambient;
  config->diffuse = splat.diffuse;
  config->specular = splat.specular;
  config->shininess = splat.shininess;
}

bool sameSplatReconfigure(const SplatConfig& a, const SplatConfig& b) {
  relaxed_connectivity::SplatConfig ca, cb;
  writeSplatReconfigure(a, &ca);
  writeSplatReconfigure(b, &cb);
  return ca.ewa_filter == cb.ewa_filter && ca.lowpass_variance == cb.lowpass_variance &&
         ca.cutoff_radius == cb.cutoff_radius && ca.depth_tolerance_scale == cb.depth_tolerance_scale &&
         ca.exact_footprint == cb.exact_footprint && ca.exact_silhouettes == cb.exact_silhouettes &&
         ca.backface_culling == cb.backface_culling && ca.shading == cb.shading && ca.ambient == cb.ambient &&
         ca.diffuse == cb.diffuse && ca.specular == cb.specular && ca.shininess == cb.shininess;
}

bool cameraPoseMoved(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b, double tolerance) {
  const double translation = (a.translation() - b.translation()).norm();
  const double angle = Eigen::AngleAxisd(a.linear().transpose() * b.linear()).angle();
  return !(translation <= tolerance && std::abs(angle) <= tolerance);
}

}  // namespace rc
