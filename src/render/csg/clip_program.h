// Per-frame compiled form of the CSG fragment test of one clipped surfel (thesis 4.2.2). For a surfel that
// is not seen edge-on, the point x(u, v) of its plane seen through pixel (u, v) is a projective function of
// the pixel, x - c = E(u, v) / D(u, v) with E and D affine. Hence every test Algorithms 4.2-4.4 make on x is
// the sign of an AFFINE function of the pixel:
//  - a partner surfel (c_j, n_j) clips x (4.3) iff  s (n_j . E + n_j . (c - c_j) D) >= 0;
//  - ranking partners by distance (4.4) compares  s (|c_j - c|^2 D - 2 E . (c_j - c)), i.e. |x - c_j|^2 up to
//    the common positive factor |D| and the common term |x - c|^2 (s = sign D, constant over the splat).
// The tree of Algorithm 4.2 reduces per surfel to a Boolean expression over the patches that have partners
// (the others are `unknown` for the whole surfel and drop out by (4.9)/(4.10)), evaluated on lane masks.
// So a fragment costs a few multiply-adds per partner in float, four pixels at a time.
#pragma once

#include <cstdint>
#include <vector>

#include "relaxed_connectivity/core/surfel_cloud.h"
#include "relaxed_connectivity/render/splat/ewa_splat.h"

namespace rc {

/// The pixel-to-plane map of one splat: x(u, v) - center = E(du, dv) / D(du, dv), du = u - u0, dv = v - v0
/// with the integer origin (u0, v0) near the splat centre; E = e0 + e_u du + e_v dv, D = d0 + d_u du + d_v
/// dv.
struct ClipFrame {
  Vec3 center;        ///< surfel centre, world frame
  Vec3 e0, e_u, e_v;  ///< world frame
  double d0, d_u, d_v;
  double sign;  ///< sign of D at the origin (+1 or -1)
  /// D changes sign over the box: the surfel plane's horizon crosses the splat; pixels beyond it (s D <= 0)
  /// see the plane behind the camera and are never kept.
  bool horizon = false;
  int32_t u0, v0;  ///< origin pixel
};

/// ClipFrame of a splat for `camera` over the pixel box [x0, x1] x [y0, y1]. False if the surfel is seen
/// edge-on (the caller then tests fragments with fragmentWorldPoint()) or the numbers are not finite.
bool makeClipFrame(const SplatGeometry& geometry, const CameraFrame& camera, int x0, int y0, int x1, int y1,
                   ClipFrame* frame);

/// An affine function of the pixel offset, c0 + cu du + cv dv.
struct ClipAffine {
  float c0, cu, cv;
};

class ClipProgram {
 public:
  static constexpr int kMaxGroupSize = 32;  ///< partners of one patch (concavity bit rows)
  static constexpr int kMaxStack = 32;      ///< expression depth

  /// Starts an empty program for a splat with pixel map `frame` (keeps the memory).
  void reset(const ClipFrame& frame);
  /// Adds the clipping partners of one patch (`ids` into centers/normals, world frame, unit normals) as the
  /// next group; returns its index, or -1 (program unusable) if count is 0 or above kMaxGroupSize or a
  /// coefficient is not finite.
  int addGroup(const uint32_t* ids, size_t count, const Vec3* centers, const Vec3* normals);
  // Postfix code of the Boolean expression (Algorithm 4.2 with the patches without partners removed).
  void pushGroup(int group, bool inverted);  ///< inside(group), or its complement
  void pushAnd();
  void pushOr();
  void levelIntersection();  ///< pops `in`: on &= in  (4.5)
  void levelUnion();         ///< pops `in`: on &= !in (4.6)
  /// Marks the program unusable (the caller falls back to the per-fragment test).
  void invalidate() { valid_ = false; }
  /// True if every group was accepted and the code is balanced.
  bool valid() const;

  int32_t u0() const { return frame_.u0; }
  int32_t v0() const { return frame_.v0; }
  size_t groupCount() const { return groups_.size(); }
  size_t partnerCount() const { return planes_.size(); }

  /// Keep bits of the pixels of row v0 + dv among `candidates` (bit b: pixel u0 + du0 + b, b < 64): the
  /// candidates that are on the CSG surface. Single-partner groups cost O(log width) per row (their test
  /// is monotone along the row), larger groups four pixels at a time.
  uint64_t keepRow(int dv, int du0, uint64_t candidates) const;
  /// Same for the one pixel (u0 + du, v0 + dv).
  bool keep(int du, int dv) const { return keepRow(dv, du, 1) & 1; }

 private:
  struct Group {
    uint16_t first, count;
  };
  enum Op : uint16_t { kGroup = 0, kAnd = 1, kOr = 2, kLevelIntersection = 3, kLevelUnion = 4 };
  /// Inside masks of group g for four pixels (bit k: pixel du + k) from the partners `active[0..count)`
  /// (ascending indices within the group, at least two) that can be among the two closest there.
  int insideMask4(const Group& g, const uint8_t* active, int count, int du, int dv) const;
  /// Inside bits of group g along a row (same bit layout as keepRow), restricted to `candidates`.
  uint64_t insideRow(const Group& g, int dv, int du0, uint64_t candidates) const;

  std::vector<ClipAffine> planes_;  ///< >= 0: the partner clips the pixel's point (4.3)
  std::vector<ClipAffine> ranks_;   ///< smaller: the partner is closer to the pixel's point (4.4)
  std::vector<uint32_t> concave_;  ///< bit k of entry j: partners j and k of one group are concave (Fig. 4.2)
  std::vector<Group> groups_;
  std::vector<uint16_t> code_;  ///< op in the low 3 bits; kGroup: inverted bit 3, group index from bit 4
  ClipFrame frame_{};
  ClipAffine front_{};        ///< s D > 0: the pixel's ray meets the plane in front of the camera
  bool has_horizon_ = false;  ///< D changes sign over the splat box (front_ is tested)
  int depth_ = 0, levels_ = 0;
  bool valid_ = true;
};

}  // namespace rc
