// MLS surfaces of thesis 3.1 over a surfel cloud: the simplified projection (Adamson-Alexa, 3.5-3.7), Levin's
// two-step projection with a bivariate polynomial (3.1-3.4), and algebraic sphere fits (APSS,
// Guennebaud-Gross).
#pragma once

#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "relaxed_connectivity/core/kd_tree.h"
#include "relaxed_connectivity/core/surfel_cloud.h"
#include "relaxed_connectivity/core/weight_function.h"

namespace rc {

class NeighborLists;

enum class MlsFit {
  kPlane,       ///< simplified MLS, Psi_S(x) = q(x) iterated to a fixed point (3.5-3.7)
  kPolynomial,  ///< Levin: plane, then a bivariate polynomial of `polynomial_degree` (3.1-3.4)
  kSphere,      ///< algebraic point set surface (APSS): the highest-accuracy option
};
MlsFit parseMlsFit(const std::string& name);  // "plane", "polynomial", "sphere"
const char* mlsFitName(MlsFit fit);

enum class MlsNormalSource {
  kCovariance,  ///< normal of the fit itself (smallest eigenvector / polynomial / sphere gradient)
  kHermite,     ///< weighted average of input normals (3.8); requires normals
};

struct MlsConfig {
  MlsFit fit = MlsFit::kPlane;
  WeightFunction weight = WeightFunction::wendland(0.1);  ///< support radius is the main speed/accuracy knob
  MlsNormalSource normal_source = MlsNormalSource::kCovariance;
  int polynomial_degree = 2;  ///< for kPolynomial (1..3)
  int max_iterations = 20;    ///< projection fixed-point iterations
  double tolerance = 1e-10;   ///< stop when a step moves less than tolerance * support radius
  size_t min_neighbors = 4;   ///< fewer weighted neighbours: the projection is reported invalid
  /// false: a projection that stops at max_iterations without converging is still reported valid (used to
  /// study iteration caps); true: it is reported invalid.
  bool require_convergence = true;
  /// Sample normals for the fits that use them (kSphere with normals, kHermite (3.8)). false: the cloud's
  /// normals (without them kSphere is the point-only fit). true: estimated from the positions, ignoring the
  /// cloud's normals: the weighted covariance normal (3.5) at every sample under this weight
  /// (estimatePlaneNormals, once per surface on first use; projectInputs takes them from its neighbour
  /// lists), each neighbourhood orienting them like the normal of the sample nearest the evaluation point.
  /// Output normals are then unoriented.
  bool estimate_normals = false;
  /// With estimate_normals: passes of refineNormalsBySpheres after the plane normals (0: plane normals only).
  /// One pass costs about one projection step and smooths the plane normals' noise (bench_mls, table (c)).
  int normal_refinement_passes = 0;
};

struct MlsProjection {
  Vec3 point = Vec3::Zero();
  Vec3 normal = Vec3::Zero();  ///< unit; oriented like the input normals when the cloud has them
  bool valid = false;          ///< false: too few neighbours, degenerate fit, or no convergence
  int iterations = 0;
};

/// An MLS surface over a cloud (the cloud must outlive it and not change). Query functions are const and
/// thread-safe and accept any point in space, not only the inputs.
class MlsSurface {
 public:
  MlsSurface(const SurfelCloud& cloud, const MlsConfig& config);
  ~MlsSurface();

  const MlsConfig& config() const { return config_; }
  const SurfelCloud& cloud() const { return cloud_; }
  /// The kd-tree over the cloud, built on first use (thread-safe).
  const KdTree& tree() const;

  MlsProjection project(const Vec3& x) const;
  /// Multi-threaded projection of many points.
  void projectBatch(const std::vector<Vec3>& xs, std::vector<MlsProjection>& out) const;

  /// Where the neighbourhoods of projectInputs() came from.
  struct InputStats {
    size_t own_list = 0;       ///< the precomputed list of the start point (always the first iteration)
    size_t neighbor_list = 0;  ///< the list of another input within the list margin of the moved point
    size_t tree = 0;           ///< kd-tree radius query (the point moved too far from every listed input)
  };
  /// Projects every point of the cloud (out[i] is the projection of cloud().positions[i]); the same result as
  /// project() on each of them up to rounding (the neighbourhoods are the same sets). Batched and
  /// multi-threaded (OpenMP): all-pairs neighbour lists are built once (rc::NeighborLists, at the support
  /// radius, or 20% beyond it when points are revisited) and the first iteration of every point runs from its
  /// list; later iterations reuse the list of the start point (or of a listed input) while the moved point
  /// stays within that margin, else they query the kd-tree. The samples are processed as copies sorted by
  /// grid cell, so that neighbourhood sums read nearby memory. A cloud with non-finite positions falls back
  /// to projectBatch(). List buffers up to ~32 MB are kept per calling thread for the next call.
  void projectInputs(std::vector<MlsProjection>& out, InputStats* stats = nullptr) const;

  /// The simplified MLS plane at x (weights w_i(x)): q(x) of (3.6) and the unit normal of (3.5) (oriented
  /// like the input normals when present). False when fewer than min_neighbors samples have weight or the fit
  /// is degenerate. This is the plane used by the ray intersection (Algorithm 3.1).
  bool fitPlane(const Vec3& x, Vec3* q, Vec3* n) const;

  /// The sample normals the fits use: the cloud's, or with estimate_normals the estimated ones (computed on
  /// first use, thread-safe). Empty when there are none.
  const std::vector<Vec3>& sampleNormals() const;

  /// Radius of the neighbourhood query: the weight's support (4 sigma for the untruncated Gaussian, where the
  /// weight has dropped to 1e-7).
  double supportRadius() const { return support_; }
  /// Process-unique instance id (never reused, unlike addresses).
  uint64_t id() const { return id_; }

 private:
  const SurfelCloud& cloud_;
  MlsConfig config_;
  mutable std::once_flag tree_once_;
  mutable std::unique_ptr<KdTree> tree_;
  mutable std::once_flag normals_once_;
  mutable std::vector<Vec3> normals_;  ///< estimate_normals only
  /// Fills normals_ once: from `lists` over `positions` (the cloud's points in `order`, lists covering the
  /// support radius) when given, else from the kd-tree.
  void estimateNormalsOnce(const NeighborLists* lists, const std::vector<Vec3>* positions,
                           const std::vector<uint32_t>* order) const;
  double support_ = 0;
  uint64_t id_ = 0;  ///< unique per instance: keys the per-thread neighbour cache
};

/// Replaces every position (and normal) by its MLS projection (MlsSurface::projectInputs); returns the number
/// of points that could not be projected (left unchanged).
size_t smoothCloud(SurfelCloud& cloud, const MlsConfig& config);

}  // namespace rc
