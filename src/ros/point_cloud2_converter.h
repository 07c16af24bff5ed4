// Conversions between rc::SurfelCloud and sensor_msgs/PointCloud2 (like grid_map's GridMapRosConverter).
// Surfels travel with the pcl::PointSurfel field layout; extra channels and unknown fields are extra fields.
#pragma once

#include <sensor_msgs/PointCloud2.h>

#include <stdexcept>
#include <string>
#include <vector>

#include "relaxed_connectivity/core/surfel_cloud.h"

namespace rc {

/// Thrown for a malformed or unsupported PointCloud2; the message names the field and the problem.
class PointCloud2Error : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

enum class PointCloud2Layout {
  /// pcl::PointSurfel, 48 bytes: x 0, y 4, z 8, normal_x 16, normal_y 20, normal_z 24, rgba 32 (uint32,
  /// packed
  /// as in PCL: bytes b g r a), radius 36, confidence 40, curvature 44. Absent channels are written as 0
  /// (PCL's
  /// defaults); the padding float at 12 is 1.0 and at 28 is 0.0, so the bytes equal pcl::toROSMsg's.
  kPointSurfel,
  /// Only the channels present, packed: x y z (float32), then normal_x/y/z, rgba, radius, confidence,
  /// curvature.
  kCompact,
};

class PointCloud2Converter {
 public:
  static constexpr uint32_t kPointSurfelStep = 48;
  /// Field names of the tangent axes of elliptical surfels (float32 each), written after the base layout.
  static const std::vector<std::string>& axisFieldNames();

  /// Fills `msg` (header.frame_id/stamp from the cloud, organised width/height kept). Tangent axes become the
  /// fields t1x t1y t1z t2x t2y t2z; every attribute column becomes a field of its own type and count
  /// (naturally aligned, in column order) holding its raw bytes. Throws PointCloud2Error if the cloud is
  /// inconsistent or an attribute name collides with a field of the layout.
  static void toMessage(const SurfelCloud& cloud, sensor_msgs::PointCloud2& msg,
                        PointCloud2Layout layout = PointCloud2Layout::kPointSurfel);
  static sensor_msgs::PointCloud2Ptr toMessage(const SurfelCloud& cloud,
                                               PointCloud2Layout layout = PointCloud2Layout::kPointSurfel);

  /// Reads any little-endian PointCloud2 with float32/float64 x, y, z (plain xyz / xyzrgb scans, PointSurfel,
  /// PointNormal, ...). Fields name channels as in PCD and PLY files (io/surfel_fields.h): x y z,
  /// normal_x/y/z or nx/ny/nz, rgba or rgb (packed; alpha 255 for rgb) or uint8 red/green/blue(/alpha),
  /// radius, confidence, curvature, t1x..t2z or axis1_x..axis2_z. Every other field (except the padding
  /// fields named _) is kept bit-exactly as an attribute column. Organised clouds (height > 1) keep
  /// width/height; NaN points are kept (use SurfelCloud::removeNonFinite). Throws PointCloud2Error naming the
  /// field for: missing x/y/z, unsupported datatype, field outside point_step, duplicate field, row_step <
  /// width * point_step, data size != row_step * height, big-endian data, and a channel field that cannot
  /// fill its channel (not float32/float64, count other than 1, a member of its group missing).
  static void fromMessage(const sensor_msgs::PointCloud2& msg, SurfelCloud& cloud);
  static SurfelCloud fromMessage(const sensor_msgs::PointCloud2& msg);

  /// Checks the header/layout consistency only (the checks of fromMessage that need no point data).
  static void checkMessage(const sensor_msgs::PointCloud2& msg);

  /// True if `msg` has exactly the pcl::PointSurfel fields at their offsets (extra fields allowed after
  /// them).
  static bool hasPointSurfelLayout(const sensor_msgs::PointCloud2& msg);
};

}  // namespace rc
