// The surfel data model shared by every module: positions plus optional normals, radii (circular surfels),
// tangent axes (elliptical surfels, thesis 3.2), colours, confidence/curvature and named extra attributes.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "relaxed_connectivity/core/attribute.h"

namespace rc {

using Vec3 = Eigen::Vector3d;
using Rgba = std::array<uint8_t, 4>;

/// Structure-of-arrays surfel cloud. `positions` defines the size; every optional channel is either empty
/// (absent) or has exactly size() elements. Geometry is double precision (floats only at message boundaries).
struct SurfelCloud {
  std::vector<Vec3> positions;
  std::vector<Vec3> normals;      ///< unit normals (optional)
  std::vector<double> radii;      ///< circular surfel radius (optional)
  std::vector<Vec3> axes1;        ///< elliptical surfel tangent axis t1, |t1| = semi-axis length (optional)
  std::vector<Vec3> axes2;        ///< elliptical surfel tangent axis t2 (optional, present iff axes1 is)
  std::vector<Rgba> colors;       ///< 8-bit RGBA (optional)
  std::vector<float> confidence;  ///< pcl::PointSurfel::confidence (optional)
  std::vector<float> curvature;   ///< surface variation (optional)
  AttributeSet attributes;        ///< named extra columns; unknown input fields are kept here

  /// Frame and time the positions are expressed in (ROS conventions; empty/0 when unknown).
  std::string frame_id;
  uint64_t stamp_ns = 0;
  /// Organised clouds (depth images): width * height == size(), invalid pixels hold NaN positions.
  /// Both 0 for unorganised clouds.
  uint32_t width = 0, height = 0;
  bool isOrganized() const { return height > 1 && width * height == size(); }

  size_t size() const { return positions.size(); }
  bool empty() const { return positions.empty(); }
  bool hasNormals() const { return !normals.empty(); }
  bool hasRadii() const { return !radii.empty(); }
  bool hasAxes() const { return !axes1.empty(); }
  bool hasColors() const { return !colors.empty(); }
  bool hasConfidence() const { return !confidence.empty(); }
  bool hasCurvature() const { return !curvature.empty(); }

  /// Resizes every present channel (and attribute) to n.
  void resize(size_t n);
  void clear();
  /// Keeps the listed elements of every channel, in that order.
  void select(const std::vector<size_t>& indices);
  /// Appends all surfels of `other`. Channels present in only one cloud are dropped (throws only if the
  /// attribute columns disagree in layout).
  void append(const SurfelCloud& other);
  /// Removes surfels whose position (or normal/radius if present) is not finite (the cloud becomes
  /// unorganised). Returns how many were removed.
  size_t removeNonFinite();
  /// Applies a rigid transform to positions, normals and tangent axes (e.g. fixed_T_cloud: into the fixed
  /// frame; frame_id is left to the caller).
  void transform(const Eigen::Isometry3d& transform);
  /// Throws std::invalid_argument naming the channel if a present channel has the wrong size.
  void validate() const;
  /// Axis-aligned bounding box; returns false for an empty cloud.
  bool bounds(Vec3* lo, Vec3* hi) const;
};

}  // namespace rc
