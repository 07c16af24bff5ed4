#include "relaxed_connectivity/render/csg/clip_program.h"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include <algorithm>
#include <cmath>
#include <limits>

#include "relaxed_connectivity/render/csg/clip_inside_patch.h"

namespace rc {

bool makeClipFrame(const SplatGeometry& geometry, const CameraFrame& camera, int x0, int y0, int x1, int y1,
                   ClipFrame* frame) {
  if (geometry.edge_on || x0 > x1 || y0 > y1) return false;
  const Vec3 c = camera.camera_R_world * geometry.center_world + camera.camera_t_world;
  const Vec3 n = camera.camera_R_world * geometry.normal_world;
  ClipFrame f;
  f.center = geometry.center_world;
  // Origin: the pixel nearest to the centre inside the box (keeps du, dv small over the box).
  f.u0 = int32_t(std::clamp(std::round(geometry.center_u), double(x0), double(x1)));
  f.v0 = int32_t(std::clamp(std::round(geometry.center_v), double(y0), double(y1)));
  Vec3 e0, e_u, e_v;
  if (camera.perspective) {
    // ray r(u, v) = ((u - cx) / fx, (v - cy) / fy, 1); D = n . r; E = (n . c) r - (n . r) c.
    const Vec3 r0((f.u0 - camera.cx) / camera.fx, (f.v0 - camera.cy) / camera.fy, 1.0);
    const double n_dot_c = n.dot(c);
    f.d0 = n.dot(r0);
    f.d_u = n.x() / camera.fx;
    f.d_v = n.y() / camera.fy;
    e0 = n_dot_c * r0 - f.d0 * c;
    e_u = Vec3(n_dot_c / camera.fx, 0, 0) - f.d_u * c;
    e_v = Vec3(0, n_dot_c / camera.fy, 0) - f.d_v * c;
  } else {
    // ray q(u, v) + t z with q = ((u - cx) / k, (v - cy) / k, 0); x - c = (q - c)_xy and the plane's z.
    const double k = camera.ortho_scale;
    const double qx = (f.u0 - camera.cx) / k - c.x(), qy = (f.v0 - camera.cy) / k - c.y();
    f.d0 = 1;
    f.d_u = f.d_v = 0;
    e0 = Vec3(qx, qy, -(n.x() * qx + n.y() * qy) / n.z());
    e_u = Vec3(1 / k, 0, -n.x() / (k * n.z()));
    e_v = Vec3(0, 1 / k, -n.y() / (k * n.z()));
  }
  // Does D keep its sign over the box? (Its extremes are at the corners.)
  if (!(std::abs(f.d0) > 0) || !std::isfinite(f.d0)) return false;
  f.sign = f.d0 > 0 ? 1.0 : -1.0;
  f.horizon = false;
  for (int y : {y0, y1})
    for (int x : {x0, x1})
      if (!(f.sign * (f.d0 + f.d_u * (x - f.u0) + f.d_v * (y - f.v0)) > 0)) f.horizon = true;
  f.e0 = camera.world_R_camera * e0;
  f.e_u = camera.world_R_camera * e_u;
  f.e_v = camera.world_R_camera * e_v;
  if (!f.e0.allFinite() || !f.e_u.allFinite() || !f.e_v.allFinite()) return false;
  *frame = f;
  return true;
}

namespace {

bool toAffine(double c0, double cu, double cv, ClipAffine* out) {
  out->c0 = float(c0);
  out->cu = float(cu);
  out->cv = float(cv);
  return std::isfinite(out->c0) && std::isfinite(out->cu) && std::isfinite(out->cv);
}

}  // namespace

void ClipProgram::reset(const ClipFrame& frame) {
  frame_ = frame;
  has_horizon_ = frame.horizon;
  if (!toAffine(frame.sign * frame.d0, frame.sign * frame.d_u, frame.sign * frame.d_v, &front_))
    has_horizon_ = false;
  planes_.clear();
  ranks_.clear();
  concave_.clear();
  groups_.clear();
  code_.clear();
  depth_ = levels_ = 0;
  valid_ = true;
}

int ClipProgram::addGroup(const uint32_t* ids, size_t count, const Vec3* centers, const Vec3* normals) {
  if (count == 0 || count > size_t(kMaxGroupSize) || groups_.size() >= 4095) {
    valid_ = false;
    return -1;
  }
  const ClipFrame& f = frame_;
  Group group;
  group.first = uint16_t(planes_.size());
  group.count = uint16_t(count);
  if (planes_.size() + count > 65535) {
    valid_ = false;
    return -1;
  }
  for (size_t k = 0; k < count; ++k) {
    const Vec3& cj = centers[ids[k]];
    const Vec3& nj = normals[ids[k]];
    const Vec3 delta = cj - f.center;
    const double nj_delta = nj.dot(delta), delta2 = delta.squaredNorm();
    ClipAffine plane, rank;
    // (4.3): s (n_j . E - (n_j . delta) D) >= 0
    const bool ok_plane =
        toAffine(f.sign * (nj.dot(f.e0) - nj_delta * f.d0), f.sign * (nj.dot(f.e_u) - nj_delta * f.d_u),
                 f.sign * (nj.dot(f.e_v) - nj_delta * f.d_v), &plane);
    // (4.4) ranking: s (|delta|^2 D - 2 E . delta)
    const bool ok_rank = toAffine(f.sign * (delta2 * f.d0 - 2 * f.e0.dot(delta)),
                                  f.sign * (delta2 * f.d_u - 2 * f.e_u.dot(delta)),
                                  f.sign * (delta2 * f.d_v - 2 * f.e_v.dot(delta)), &rank);
    if (!ok_plane || !ok_rank) {
      valid_ = false;
      return -1;
    }
    uint32_t concave = 0;
    for (size_t l = 0; l < count; ++l)
      if (l != k && surfelsConcave(cj, nj, centers[ids[l]], normals[ids[l]])) concave |= 1u << l;
    planes_.push_back(plane);
    ranks_.push_back(rank);
    concave_.push_back(concave);
  }
  groups_.push_back(group);
  return int(groups_.size()) - 1;
}

void ClipProgram::pushGroup(int group, bool inverted) {
  if (group < 0 || group >= int(groups_.size()) || ++depth_ > kMaxStack) {
    valid_ = false;
    return;
  }
  code_.push_back(uint16_t(kGroup | (inverted ? 8 : 0) | (group << 4)));
}

void ClipProgram::pushAnd() {
  if (--depth_ < 1) valid_ = false;
  code_.push_back(kAnd);
}

void ClipProgram::pushOr() {
  if (--depth_ < 1) valid_ = false;
  code_.push_back(kOr);
}

void ClipProgram::levelIntersection() {
  if (--depth_ < 0) valid_ = false;
  ++levels_;
  code_.push_back(kLevelIntersection);
}

void ClipProgram::levelUnion() {
  if (--depth_ < 0) valid_ = false;
  ++levels_;
  code_.push_back(kLevelUnion);
}

bool ClipProgram::valid() const {
  return valid_ && depth_ == 0;
}

#if defined(__SSE2__)
int ClipProgram::insideMask4(const Group& g, const uint8_t* active, int count, int du, int dv) const {
  const __m128 du4 = _mm_add_ps(_mm_set1_ps(float(du)), _mm_setr_ps(0, 1, 2, 3));
  const float fdv = float(dv);
  auto evaluate = [&](const ClipAffine& a) {
    return _mm_add_ps(_mm_set1_ps(a.c0 + a.cv * fdv), _mm_mul_ps(_mm_set1_ps(a.cu), du4));
  };
  const __m128 zero = _mm_setzero_ps();
  // The two closest partners per pixel (first of equal ranks wins, as in insidePatchFromSurfels), with
  // their indices and plane values.
  __m128 best0 = _mm_set1_ps(std::numeric_limits<float>::infinity()), best1 = best0;
  __m128 index0 = zero, index1 = zero;  // partner index as float
  __m128 plane0 = zero, plane1 = zero;
  auto choose = [](__m128 mask, __m128 a, __m128 b) {
    return _mm_or_ps(_mm_and_ps(mask, a), _mm_andnot_ps(mask, b));
  };
  for (int a = 0; a < count; ++a) {
    const int k = active[a];
    const __m128 r = evaluate(ranks_[g.first + k]), p = evaluate(planes_[g.first + k]);
    const __m128 kf = _mm_set1_ps(float(k));
    const __m128 lt0 = _mm_cmplt_ps(r, best0), lt1 = _mm_cmplt_ps(r, best1);
    best1 = choose(lt0, best0, choose(lt1, r, best1));
    index1 = choose(lt0, index0, choose(lt1, kf, index1));
    plane1 = choose(lt0, plane0, choose(lt1, p, plane1));
    best0 = choose(lt0, r, best0);
    index0 = choose(lt0, kf, index0);
    plane0 = choose(lt0, p, plane0);
  }
  const int in_a = ~_mm_movemask_ps(_mm_cmpge_ps(plane0, zero)) & 0xF;
  const int in_b = ~_mm_movemask_ps(_mm_cmpge_ps(plane1, zero)) & 0xF;
  alignas(16) float i0[4], i1[4];
  _mm_store_ps(i0, index0);
  _mm_store_ps(i1, index1);
  int concave = 0;
  for (int lane = 0; lane < 4; ++lane)
    concave |= int((concave_[g.first + int(i0[lane])] >> int(i1[lane])) & 1u) << lane;
  return (concave & (in_a | in_b)) | (~concave & in_a & in_b);  // (4.4)
}
#else
int ClipProgram::insideMask4(const Group& g, const uint8_t* active, int count, int du, int dv) const {
  const float fdv = float(dv);
  int inside = 0;
  for (int lane = 0; lane < 4; ++lane) {
    const float x = float(du + lane);
    auto value = [&](const ClipAffine& a) { return a.c0 + a.cv * fdv + a.cu * x; };
    float best0 = std::numeric_limits<float>::infinity(), best1 = best0;
    int a = 0, b = 0;
    for (int j = 0; j < count; ++j) {
      const int k = active[j];
      const float r = value(ranks_[g.first + k]);
      if (r < best0) {
        best1 = best0;
        b = a;
        best0 = r;
        a = k;
      } else if (r < best1) {
        best1 = r;
        b = k;
      }
    }
    a += g.first;
    b += g.first;
    const bool in_a = !(value(planes_[a]) >= 0.0f), in_b = !(value(planes_[b]) >= 0.0f);
    const bool concave = (concave_[a] >> (b - g.first)) & 1u;
    inside |= int(concave ? (in_a || in_b) : (in_a && in_b)) << lane;
  }
  return inside;
}
#endif

namespace {

int lowestBit(uint64_t bits) {
  return __builtin_ctzll(bits);
}
int highestBit(uint64_t bits) {
  return 63 - __builtin_clzll(bits);
}
uint64_t bitsBelow(int b) {
  return b >= 64 ? ~uint64_t(0) : (uint64_t(1) << b) - 1;
}

/// Bits b of `candidates` where value(b) >= 0, for a value non-decreasing or non-increasing in b (an affine
/// function evaluated in float along a row is monotone): binary search for the switch.
template <class Value>
uint64_t nonNegativeBits(uint64_t candidates, Value&& value) {
  const int lo = lowestBit(candidates), hi = highestBit(candidates);
  const bool first = value(lo) >= 0.0f, last = value(hi) >= 0.0f;
  if (first == last) return first ? candidates : 0;
  int a = lo, b = hi;  // value(a) on the `first` side, value(b) on the `last` side
  while (b - a > 1) {
    const int m = a + (b - a) / 2;
    if ((value(m) >= 0.0f) == last) {
      b = m;
    } else {
      a = m;
    }
  }
  const uint64_t below = bitsBelow(b);  // bits < b have `first`, bits >= b have `last`
  return candidates & (first ? below : ~below);
}

}  // namespace

uint64_t ClipProgram::insideRow(const Group& g, int dv, int du0, uint64_t candidates) const {
  const float fdv = float(dv);
  if (g.count == 1) {  // (4.3): inside iff the plane value is negative
    const ClipAffine& p = planes_[g.first];
    const float row = p.c0 + p.cv * fdv;
    return candidates & ~nonNegativeBits(candidates, [&](int b) { return row + p.cu * float(du0 + b); });
  }
  // Partners that can be among the two closest somewhere on the span: a rank is monotone along the row, so
  // its range over the span is between its end values; a partner whose smallest rank exceeds the second
  // smallest of the largest ranks is never among the two closest (4.4).
  const int lo = lowestBit(candidates), hi = highestBit(candidates);
  float range_lo[kMaxGroupSize], largest0 = std::numeric_limits<float>::infinity(), largest1 = largest0;
  for (int k = 0; k < g.count; ++k) {
    const ClipAffine& r = ranks_[g.first + k];
    const float row = r.c0 + r.cv * fdv;
    const float a = row + r.cu * float(du0 + lo), b = row + r.cu * float(du0 + hi);
    range_lo[k] = std::min(a, b);
    const float range_hi = std::max(a, b);
    if (range_hi < largest0) {
      largest1 = largest0;
      largest0 = range_hi;
    } else if (range_hi < largest1) {
      largest1 = range_hi;
    }
  }
  uint8_t active[kMaxGroupSize];
  int count = 0;
  for (int k = 0; k < g.count; ++k)
    if (range_lo[k] <= largest1) active[count++] = uint8_t(k);
  if (count == 2) {  // the same two partners everywhere on the span: two monotone plane tests (4.4)
    const int a = g.first + active[0], b = g.first + active[1];
    auto insideOf = [&](const ClipAffine& p) {
      const float row = p.c0 + p.cv * fdv;
      return candidates &
             ~nonNegativeBits(candidates, [&](int bit) { return row + p.cu * float(du0 + bit); });
    };
    const uint64_t in_a = insideOf(planes_[a]), in_b = insideOf(planes_[b]);
    return ((concave_[a] >> active[1]) & 1u) ? (in_a | in_b) : (in_a & in_b);
  }
  uint64_t inside = 0;
  for (int b = lo; b <= hi; b += 4)
    if ((candidates >> b) & 0xF) inside |= uint64_t(insideMask4(g, active, count, du0 + b, dv)) << b;
  return inside & candidates;
}

uint64_t ClipProgram::keepRow(int dv, int du0, uint64_t candidates) const {
  if (has_horizon_ && candidates) {  // only pixels whose ray meets the plane in front of the camera
    const float row = front_.c0 + front_.cv * float(dv);
    candidates &= ~nonNegativeBits(candidates, [&](int b) { return -(row + front_.cu * float(du0 + b)); });
  }
  if (!candidates) return 0;
  uint64_t stack[kMaxStack];
  int top = 0;
  uint64_t on = candidates;
  for (const uint16_t instruction : code_) {
    switch (instruction & 7) {
      case kGroup: {
        const uint64_t inside = insideRow(groups_[instruction >> 4], dv, du0, on);
        stack[top++] = (instruction & 8) ? (on & ~inside) : inside;
        break;
      }
      case kAnd:
        --top;
        stack[top - 1] &= stack[top];
        break;
      case kOr:
        --top;
        stack[top - 1] |= stack[top];
        break;
      case kLevelIntersection:  // (4.5)
        on &= stack[--top];
        if (!on) return 0;
        break;
      case kLevelUnion:  // (4.6)
        on &= ~stack[--top];
        if (!on) return 0;
        break;
    }
  }
  return on;
}

}  // namespace rc
