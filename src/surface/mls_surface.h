// MLS surfaces of thesis 3.1 over a surfel cloud: the simplified projection (Adamson-Alexa, 3.5-3.7), Levin's
// two-step projection with a bivariate polynomial (3.1-3.4), and algebraic sphere fits (APSS, Guennebaud-Gross).
#pragma once

#include <memory>
#include <vector>

#include "core/kd_tree.h"
#include "core/surfel_cloud.h"
#include "core/weight_function.h"

namespace rc {

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
  int polynomial_degree = 2;   ///< for kPolynomial (1..3)
  int max_iterations = 20;     ///< projection fixed-point iterations
  double tolerance = 1e-10;    ///< stop when a step moves less than tolerance * support radius
  size_t min_neighbors = 4;    ///< fewer weighted neighbours: the projection is reported invalid
};

struct MlsProjection {
  Vec3 point = Vec3::Zero();
  Vec3 normal = Vec3::Zero();  ///< unit; oriented like the input normals when the cloud has them
  bool valid = false;          ///< false: too few neighbours, degenerate fit, or no convergence
  int iterations = 0;
};

/// An MLS surface over a cloud (the cloud must outlive it). Query functions are const and thread-safe and accept
/// any point in space, not only the inputs.
class MlsSurface {
 public:
  MlsSurface(const SurfelCloud& cloud, const MlsConfig& config);
  ~MlsSurface();

  const MlsConfig& config() const { return config_; }
  const SurfelCloud& cloud() const { return cloud_; }
  const KdTree& tree() const { return *tree_; }

  MlsProjection project(const Vec3& x) const;
  /// Multi-threaded projection of many points.
  void projectBatch(const std::vector<Vec3>& xs, std::vector<MlsProjection>& out) const;

 private:
  const SurfelCloud& cloud_;
  MlsConfig config_;
  std::unique_ptr<KdTree> tree_;
};

/// Replaces every position (and normal) by its MLS projection; returns the number of points that could not be
/// projected (left unchanged).
size_t smoothCloud(SurfelCloud& cloud, const MlsConfig& config);

}  // namespace rc
