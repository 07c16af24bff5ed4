// Surface animation of a point-sampled thin shell (thesis 7.4): every surfel of the dense cloud follows the
// simulation nodes through local frames (7.26-7.30) — positions, normals and tangent axes — and cracks
// (7.3.2) give paired discontinuity surfels (4.3) that are animated the same way.
#pragma once

#include <cstdint>
#include <string>
#include <unordered_map>
#include <vector>

#include "relaxed_connectivity/core/surfel_cloud.h"
#include "relaxed_connectivity/shell/shell_crack.h"
#include "relaxed_connectivity/shell/shell_nodes.h"

namespace rc {

struct ShellSkinningOptions {
  /// Size of P_p (x_0 .. x_{n_p}): the nearest visible nodes of each surfel (>= 2).
  size_t node_count = 8;
};

/// Binds a rest surfel cloud to shell nodes and deforms it with them.
///
/// For surfel p with nodes x_0..x_{n_p} (nearest first, only nodes not separated from p by a crack): N is
/// the least-squares plane normal of the nodes (oriented along their normals; deformed: along their fan
/// normals), frames e_1 = x_i - x_0, e_2 = N x e_1 / |e_1|, e_3 = e_2 x e_1 / |e_1| (7.26), coordinates
/// y_k = (p - x_0) . e_k / |e_k|^2 (7.27), and the deformed point is the blend (7.28, 7.29) with weights
/// w(t) = ((1 - t^2) / t)^2 of t = |x_i - p| / |x_{n_p} - p| (7.30: w(0) = inf, w(1) = 0). Normals and
/// tangent axes are mapped as vectors by the same frames (normals renormalised).
///
/// Discontinuity surfels (int32 attribute "surfel_role" == 1) are bound on the material side opposite their
/// normal, so each surfel of a crack pair follows its own piece.
class ShellSkinning {
 public:
  ShellSkinning(const SurfelCloud& rest, const ShellNodes& nodes, const std::vector<ShellCrack>& cracks = {},
                const ShellSkinningOptions& options = ShellSkinningOptions());

  /// Writes positions, normals and (if the rest cloud has them) axes of `out` for node positions x (size of
  /// nodes). `out` keeps its other channels; it is resized to the rest cloud's size if it differs. Not
  /// thread-safe on one object (per-call scratch); parallelises internally.
  void deform(const ShellNodes& nodes, const std::vector<Vec3>& x, SurfelCloud* out) const;

  /// Incremental re-binding after new cracks (7.3.2): `rest` is the bound cloud, possibly with surfels
  /// appended (their bindings are made), and `cracks` extends the cracks bound so far. Only surfels that a
  /// new crack separates from one of their nodes P_p are re-bound; for the others the nearest visible
  /// nodes cannot change, so the result equals a full binding against all cracks. A re-bound surfel that
  /// would see no node keeps its old binding; returns how many did. Throws std::invalid_argument (and
  /// changes nothing) if an appended surfel sees no node or the inputs do not extend the bound ones.
  size_t rebind(const SurfelCloud& rest, const ShellNodes& nodes, const std::vector<ShellCrack>& cracks);

  size_t size() const { return surfel_count_; }
  /// Cracks the binding respects (those given to the constructor and to rebind()).
  size_t boundCracks() const { return bound_cracks_; }
  /// Surfels re-bound by the last rebind() call (appended ones included).
  size_t lastRebound() const { return last_rebound_; }

 private:
  struct Binder;
  bool bindSurfel(const Binder& b, size_t s, uint32_t* ids, uint8_t* set_size, uint8_t* frame_count,
                  uint8_t* frame_slots, double* weights, Vec3* coords) const;
  /// Points surfel s at the distinct node set of its P_p (added if new).
  void assignPlaneSet(size_t s);

  size_t bound_cracks_ = 0;
  size_t last_rebound_ = 0;
  size_t surfel_count_ = 0;
  size_t node_count_ = 0;  ///< stride of node_ids_
  bool has_axes_ = false;
  std::vector<uint32_t> node_ids_;    ///< per surfel (stride node_count_): P_p, nearest first
  std::vector<uint8_t> set_size_;     ///< |P_p| per surfel
  std::vector<uint8_t> frame_count_;  ///< frames with positive weight per surfel
  std::vector<uint8_t> frame_slots_;  ///< per frame (stride node_count_ - 1): index i of x_i in P_p
  std::vector<double> weights_;       ///< per frame, normalised
  std::vector<Vec3> coords_;          ///< per frame: position, normal[, axis1, axis2] coordinates
  /// Distinct node sets P_p (sorted ids): the plane normal of a set is computed once per deform, not per
  /// surfel (many surfels share their nearest nodes).
  std::vector<uint32_t> plane_set_;                      ///< per surfel: index of its set
  std::vector<uint32_t> set_ids_;                        ///< per set (stride node_count_): sorted node ids
  std::vector<uint8_t> set_sizes_;                       ///< per set
  std::unordered_map<std::string, uint32_t> set_index_;  ///< sorted ids (bytes) -> set
  mutable std::vector<Vec3> set_normals_, fan_;          ///< deform() scratch
};

/// One pair of discontinuity surfels per crack (7.3.2, 4.3), in rest coordinates: centred on the crack disc,
/// normals +n and -n, circular radius and axes spanning the disc. Int32 attributes "surfel_role" = 1
/// (SurfelRole::kDiscontinuity, core/surfel_attributes.h), "patch_id" = 1 + crack index (the surface is patch
/// 0) and "crack_side"
/// (+1 / -1, the sign of the normal).
SurfelCloud crackDiscontinuitySurfels(const std::vector<ShellCrack>& cracks);

}  // namespace rc
