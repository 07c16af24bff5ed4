// Stored plasticity of SphElasticSolid (thesis 8.2.5, beside the inherent plasticity): the plastic flow of a
// neighbourhood's shape, volume preserving, with the plastic stretch kept within max_plastic_strain.
#include <algorithm>
#include <cmath>

#include <Eigen/Dense>

#include "relaxed_connectivity/sph/sph_elastic_solid.h"

namespace rc {

using Mat3 = Eigen::Matrix3d;

void SphElasticSolid::updatePlasticity(uint32_t i, const Mat3& v, const Vec3& sigma) {
  const int dim = lattice_.dimension();
  Vec3 excess = sigma - Vec3::Ones();
  if (dim == 2) excess.z() = 0.0;
  const double e = excess.norm();
  if (!(e > config_.yield_strain) || !(sigma.x() > 0.0 && sigma.y() > 0.0 && sigma.z() > 0.0)) return;
  const double a = -std::expm1(-config_.plastic_flow_rate * step_dt_) * (e - config_.yield_strain) / e;
  Vec3 flow = Vec3::Ones();  // S / S'
  for (int k = 0; k < dim; ++k) flow[k] = sigma[k] / (1.0 + (1.0 - a) * excess[k]);
  flow /= std::pow(dim == 3 ? flow.prod() : flow.x() * flow.y(), 1.0 / dim);  // volume preserving
  if (dim == 2) flow.z() = 1.0;
  Mat3 p = v * flow.asDiagonal() * v.transpose() * plastic_[i];
  // Keep the singular values of P in [1 / (1 + c), 1 + c].
  Mat3 pu, pv;
  Vec3 ps;
  rotationSvd(p, dim, pu, ps, pv);
  const double c = 1.0 + config_.max_plastic_strain;
  double log_stretch = 0.0;
  for (int k = 0; k < dim; ++k) {
    ps[k] = std::clamp(ps[k], 1.0 / c, c);
    log_stretch = std::max(log_stretch, std::abs(std::log(ps[k])));
  }
  p = pu * ps.asDiagonal() * pv.transpose();
  if (!p.allFinite()) return;
  plastic_[i] = p;
  plastic_strain_[i] = log_stretch;
}

}  // namespace rc
