#include "relaxed_connectivity/surface/mls_fits.h"

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>

namespace rc {

namespace {

/// Two doubles: one SSE2 / NEON packet (Eigen vectorises its arithmetic and sqrt).
using Pack = Eigen::Array2d;
inline Pack load(const double* p) {
  return Pack::Map(p);
}

/// Orthonormal tangent frame of a unit normal.
void tangentFrame(const Vec3& n, Vec3* t1, Vec3* t2) {
  const Vec3 a = std::abs(n.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
  *t1 = n.cross(a).normalized();
  *t2 = n.cross(*t1);
}

/// Monomials 1, u, v, u^2, uv, v^2, u^3, u^2 v, u v^2, v^3 (first `terms` of them).
inline void monomials(double u, double v, int terms, double* m) {
  m[0] = 1;
  if (terms > 1) m[1] = u, m[2] = v;
  if (terms > 3) m[3] = u * u, m[4] = u * v, m[5] = v * v;
  if (terms > 6) m[6] = u * u * u, m[7] = u * u * v, m[8] = u * v * v, m[9] = v * v * v;
}

/// f, f_u, f_v, f_uu, f_uv, f_vv of the polynomial with coefficients c.
void evalPolynomial(const double* c, int terms, double u, double v, double* d) {
  double f = c[0], fu = 0, fv = 0, fuu = 0, fuv = 0, fvv = 0;
  if (terms > 1) f += c[1] * u + c[2] * v, fu += c[1], fv += c[2];
  if (terms > 3) {
    f += c[3] * u * u + c[4] * u * v + c[5] * v * v;
    fu += 2 * c[3] * u + c[4] * v, fv += c[4] * u + 2 * c[5] * v;
    fuu += 2 * c[3], fuv += c[4], fvv += 2 * c[5];
  }
  if (terms > 6) {
    f += c[6] * u * u * u + c[7] * u * u * v + c[8] * u * v * v + c[9] * v * v * v;
    fu += 3 * c[6] * u * u + 2 * c[7] * u * v + c[8] * v * v;
    fv += c[7] * u * u + 2 * c[8] * u * v + 3 * c[9] * v * v;
    fuu += 6 * c[6] * u + 2 * c[7] * v, fuv += 2 * c[7] * u + 2 * c[8] * v,
        fvv += 2 * c[8] * u + 6 * c[9] * v;
  }
  d[0] = f, d[1] = fu, d[2] = fv, d[3] = fuu, d[4] = fuv, d[5] = fvv;
}

}  // namespace

size_t MlsLocalSamples::gather(const Vec3* positions, const Vec3* normals, const uint32_t* ids, size_t n,
                               uint32_t extra, const Vec3& p, double support, const WeightFunction& weight,
                               bool orient_normals) {
  const size_t capacity = n + 1 + kLanes;
  if (x.size() < capacity) {
    const size_t grown = std::max(capacity, 2 * x.size());
    for (std::vector<double>* v : {&x, &y, &z, &sq_norm, &w, &nx, &ny, &nz}) v->resize(grown);
  }
  has_normals = normals != nullptr;
  const double inv = 1.0 / support, px = p.x(), py = p.y(), pz = p.z();
  double *X = x.data(), *Y = y.data(), *Z = z.data(), *D = sq_norm.data();
  size_t c = 0;
  // Branch-free compaction: every candidate is written at slot c, which only advances when it is inside.
  auto take = [&](uint32_t id) {
    const Vec3& q = positions[id];
    const double dx = (q.x() - px) * inv, dy = (q.y() - py) * inv, dz = (q.z() - pz) * inv;
    const double d2 = dx * dx + dy * dy + dz * dz;
    X[c] = dx, Y[c] = dy, Z[c] = dz, D[c] = d2;
    if (normals) {
      const Vec3& m = normals[id];
      nx[c] = m.x(), ny[c] = m.y(), nz[c] = m.z();
    }
    c += d2 < 1.0;  // NaN: never inside
  };
  for (size_t k = 0; k < n; ++k) take(ids[k]);
  if (extra != kNoExtra) take(extra);

  double* W = w.data();
  // Gaussians (3.10)-(3.11) in units of the support: w = exp(-f |y|^2), f = (support / sigma)^2, positive
  // for every gathered sample when the support does not exceed the clip radius (always so in MlsSurface).
  const bool gaussian =
      weight.kind == WeightKind::kGaussian ||
      (weight.kind == WeightKind::kClippedGaussian && support <= weight.clip * weight.scale);
  if (weight.kind != WeightKind::kWendlandC2 && !gaussian) {
    const double r2 = support * support;
    size_t kept = 0;
    for (size_t k = 0; k < c; ++k) {
      const double wk = weight.fromSquared(D[k] * r2);
      X[kept] = X[k], Y[kept] = Y[k], Z[kept] = Z[k], D[kept] = D[k], W[kept] = wk;
      if (normals) nx[kept] = nx[k], ny[kept] = ny[k], nz[kept] = nz[k];
      kept += wk > 0;
    }
    c = kept;
  }
  count = c;
  padded = (c + kLanes - 1) / kLanes * kLanes;
  for (size_t k = c; k < padded; ++k) {
    X[k] = Y[k] = Z[k] = D[k] = W[k] = 0;
    nx[k] = ny[k] = nz[k] = 0;
  }
  if (weight.kind == WeightKind::kWendlandC2) {
    // (3.12) in units of the support, q = |y|, two samples per SIMD packet; the padding gets weight 0.
    for (size_t k = 0; k < padded; k += 2) {
      const Pack q = Pack::Map(D + k).sqrt(), a = 1.0 - q, a2 = a * a;
      Pack::Map(W + k) = a2 * a2 * (1.0 + 4.0 * q);
    }
    for (size_t k = c; k < padded; ++k) W[k] = 0;
  } else if (gaussian) {
    const double f = (support / weight.scale) * (support / weight.scale);
    for (size_t k = 0; k < padded; k += 2) Pack::Map(W + k) = (-f * Pack::Map(D + k)).exp();
    for (size_t k = c; k < padded; ++k) W[k] = 0;
  }
  if (normals && orient_normals && c > 0) {
    // Reference: the nonzero normal of the nearest sample (estimated normals are zero where the fit failed).
    size_t ref = c;
    double best = std::numeric_limits<double>::infinity();
    for (size_t k = 0; k < c; ++k) {
      const bool usable = nx[k] != 0 || ny[k] != 0 || nz[k] != 0;
      if (usable && D[k] < best) best = D[k], ref = k;
    }
    if (ref < c) {
      const double rx = nx[ref], ry = ny[ref], rz = nz[ref];
      for (size_t k = 0; k < c; ++k) {
        const double s = nx[k] * rx + ny[k] * ry + nz[k] * rz < 0 ? -1.0 : 1.0;
        nx[k] *= s, ny[k] *= s, nz[k] *= s;
      }
    }
  }
  return count;
}

bool fitLocalPlane(const MlsLocalSamples& s, Vec3* q, Vec3* n) {
  // One pass: weight, first and second moments, normal sum (two samples per packet).
  Pack acc[13];
  for (Pack& a : acc) a.setZero();
  const double *X = s.x.data(), *Y = s.y.data(), *Z = s.z.data(), *W = s.w.data();
  for (size_t k = 0; k < s.padded; k += 2) {
    const Pack w = load(W + k), x = load(X + k), y = load(Y + k), z = load(Z + k);
    const Pack wx = w * x, wy = w * y, wz = w * z;
    acc[0] += w, acc[1] += wx, acc[2] += wy, acc[3] += wz;
    acc[4] += wx * x, acc[5] += wx * y, acc[6] += wx * z;
    acc[7] += wy * y, acc[8] += wy * z, acc[9] += wz * z;
  }
  if (s.has_normals) {
    const double *NX = s.nx.data(), *NY = s.ny.data(), *NZ = s.nz.data();
    for (size_t k = 0; k < s.padded; k += 2) {
      const Pack w = load(W + k);
      acc[10] += w * load(NX + k), acc[11] += w * load(NY + k), acc[12] += w * load(NZ + k);
    }
  }
  double m[13];
  for (int j = 0; j < 13; ++j) m[j] = acc[j].sum();
  const double sw = m[0];
  if (!(sw > 0)) return false;
  const double inv_sw = 1.0 / sw;
  const Vec3 mean(m[1] * inv_sw, m[2] * inv_sw, m[3] * inv_sw);
  Eigen::Matrix3d cov;
  cov(0, 0) = m[4] * inv_sw - mean.x() * mean.x();
  cov(1, 0) = cov(0, 1) = m[5] * inv_sw - mean.x() * mean.y();
  cov(2, 0) = cov(0, 2) = m[6] * inv_sw - mean.x() * mean.z();
  cov(1, 1) = m[7] * inv_sw - mean.y() * mean.y();
  cov(2, 1) = cov(1, 2) = m[8] * inv_sw - mean.y() * mean.z();
  cov(2, 2) = m[9] * inv_sw - mean.z() * mean.z();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig;
  eig.computeDirect(cov);  // closed form (3.5)
  const Eigen::Vector3d lambda = eig.eigenvalues();
  // Collinear or coincident samples. The closed form is accurate to ~1e-9 |cov| only for a double root, hence
  // the relative threshold.
  if (!(lambda(1) > 1e-12 + 1e-6 * lambda(2)) || !std::isfinite(lambda(0))) return false;
  Vec3 normal = eig.eigenvectors().col(0).normalized();
  if (s.has_normals && normal.dot(Vec3(m[10], m[11], m[12])) < 0) normal = -normal;
  *q = mean;
  *n = normal;
  return true;
}

Vec3 localNormalSum(const MlsLocalSamples& s) {
  if (!s.has_normals) return Vec3::Zero();
  Pack acc[3];
  for (Pack& a : acc) a.setZero();
  const double *W = s.w.data(), *NX = s.nx.data(), *NY = s.ny.data(), *NZ = s.nz.data();
  for (size_t k = 0; k < s.padded; k += 2) {
    const Pack w = load(W + k);
    acc[0] += w * load(NX + k), acc[1] += w * load(NY + k), acc[2] += w * load(NZ + k);
  }
  const double m[3] = {acc[0].sum(), acc[1].sum(), acc[2].sum()};
  return Vec3(m[0], m[1], m[2]);
}

bool projectLocalPolynomial(const MlsLocalSamples& s, const Vec3& q, const Vec3& N, int degree, const Vec3& y,
                            Vec3* foot, Vec3* normal) {
  Vec3 t1, t2;
  tangentFrame(N, &t1, &t2);
  const Vec3 origin = y - N * N.dot(y - q);  // foot of y: Levin's constraint (3.2) puts q(x) here
  const int terms = (degree + 1) * (degree + 2) / 2;
  if (s.count < static_cast<size_t>(terms)) return false;
  using Mat = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 10, 10>;
  using Vec = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 10, 1>;
  Mat M = Mat::Zero(terms, terms);
  Vec b = Vec::Zero(terms);
  double m[10];
  for (size_t k = 0; k < s.count; ++k) {
    const Vec3 d = Vec3(s.x[k], s.y[k], s.z[k]) - origin;
    monomials(d.dot(t1), d.dot(t2), terms, m);
    const double w = s.w[k], h = d.dot(N);
    for (int i = 0; i < terms; ++i) {
      const double wm = w * m[i];
      b(i) += wm * h;  // (3.3)
      for (int j = 0; j <= i; ++j) M(i, j) += wm * m[j];
    }
  }
  for (int i = 0; i < terms; ++i)
    for (int j = i + 1; j < terms; ++j) M(i, j) = M(j, i);
  Eigen::LDLT<Mat> ldlt(M);
  if (ldlt.info() != Eigen::Success || !ldlt.isPositive() || !(ldlt.rcond() > 1e-13)) return false;
  const Vec c = ldlt.solve(b);
  // Closest point of the graph (u, v, f(u, v)) to y = (0, 0, hy): Newton on u^2 + v^2 + (f - hy)^2.
  const double hy = N.dot(y - origin);
  double u = 0, v = 0, d[6];
  for (int it = 0; it < 10; ++it) {
    evalPolynomial(c.data(), terms, u, v, d);
    const double r = d[0] - hy;
    const Eigen::Vector2d g(u + r * d[1], v + r * d[2]);
    Eigen::Matrix2d H;
    H << 1 + d[1] * d[1] + r * d[3], d[1] * d[2] + r * d[4], d[1] * d[2] + r * d[4],
        1 + d[2] * d[2] + r * d[5];
    if (!(H.determinant() > 0) || !(H(0, 0) > 0)) break;  // keep the last (at worst the vertical) foot
    const Eigen::Vector2d step = H.ldlt().solve(g);
    u -= step(0), v -= step(1);
    if (step.squaredNorm() < 1e-30) break;
  }
  evalPolynomial(c.data(), terms, u, v, d);
  if (!std::isfinite(d[0])) return false;
  *foot = origin + u * t1 + v * t2 + d[0] * N;  // (3.4)
  *normal = (N - d[1] * t1 - d[2] * t2).normalized();
  return true;
}

bool fitLocalSphereWithNormals(const MlsLocalSamples& s, LocalSphere* sphere) {
  Pack acc[9];
  for (Pack& a : acc) a.setZero();
  const double *X = s.x.data(), *Y = s.y.data(), *Z = s.z.data(), *D = s.sq_norm.data(), *W = s.w.data();
  const double *NX = s.nx.data(), *NY = s.ny.data(), *NZ = s.nz.data();
  for (size_t k = 0; k < s.padded; k += 2) {
    const Pack w = load(W + k), x = load(X + k), y = load(Y + k), z = load(Z + k);
    const Pack nx = load(NX + k), ny = load(NY + k), nz = load(NZ + k);
    acc[0] += w;
    acc[1] += w * x, acc[2] += w * y, acc[3] += w * z;
    acc[4] += w * nx, acc[5] += w * ny, acc[6] += w * nz;
    acc[7] += w * (x * nx + y * ny + z * nz);
    acc[8] += w * load(D + k);
  }
  double m[9];
  for (int j = 0; j < 9; ++j) m[j] = acc[j].sum();
  const double sw = m[0], s_pn = m[7], s_pp = m[8];
  if (!(sw > 0)) return false;
  const Vec3 sp(m[1], m[2], m[3]), sn(m[4], m[5], m[6]);
  const double inv_sw = 1.0 / sw;
  const double den = s_pp - inv_sw * sp.squaredNorm();
  sphere->uq = std::abs(den) > 1e-14 * s_pp ? 0.5 * (s_pn - inv_sw * sp.dot(sn)) / den : 0.0;
  sphere->ul = (sn - 2 * sphere->uq * sp) * inv_sw;
  sphere->u0 = -inv_sw * (sphere->ul.dot(sp) + sphere->uq * s_pp);
  return true;
}

bool fitLocalSpherePoints(const MlsLocalSamples& s, LocalSphere* sphere) {
  // Minimise sum w s(y_i)^2 under |ul|^2 - 4 u0 uq = 1: the generalised eigenproblem A u = lambda C u with
  // the smallest lambda among vectors with u^T C u > 0. A = sum w v v^T, v = (1, y, |y|^2).
  Pack acc[15];
  for (Pack& a : acc) a.setZero();
  const double *X = s.x.data(), *Y = s.y.data(), *Z = s.z.data(), *D = s.sq_norm.data(), *W = s.w.data();
  for (size_t k = 0; k < s.padded; k += 2) {
    const Pack w = load(W + k), x = load(X + k), y = load(Y + k), z = load(Z + k), d = load(D + k);
    const Pack wx = w * x, wy = w * y, wz = w * z, wd = w * d;
    acc[0] += w, acc[1] += wx, acc[2] += wy, acc[3] += wz, acc[4] += wd;
    acc[5] += wx * x, acc[6] += wx * y, acc[7] += wx * z, acc[8] += wx * d;
    acc[9] += wy * y, acc[10] += wy * z, acc[11] += wy * d;
    acc[12] += wz * z, acc[13] += wz * d, acc[14] += wd * d;
  }
  double m[15];
  for (int j = 0; j < 15; ++j) m[j] = acc[j].sum();
  Eigen::Matrix<double, 5, 5> A;
  A << m[0], m[1], m[2], m[3], m[4],    //
      m[1], m[5], m[6], m[7], m[8],     //
      m[2], m[6], m[9], m[10], m[11],   //
      m[3], m[7], m[10], m[12], m[13],  //
      m[4], m[8], m[11], m[13], m[14];
  Eigen::Matrix<double, 5, 5> CinvA = A;  // C^-1 swaps rows 0 and 4 with factor -1/2
  CinvA.row(0) = -0.5 * A.row(4);
  CinvA.row(4) = -0.5 * A.row(0);
  Eigen::EigenSolver<Eigen::Matrix<double, 5, 5>> es(CinvA);
  if (es.info() != Eigen::Success) return false;
  double best = std::numeric_limits<double>::infinity();
  Eigen::Matrix<double, 5, 1> u;
  bool found = false;
  for (int i = 0; i < 5; ++i) {
    const Eigen::Matrix<double, 5, 1> e = es.eigenvectors().col(i).real();
    const double pratt = e.segment<3>(1).squaredNorm() - 4 * e(0) * e(4);
    if (!(pratt > 1e-12 * e.squaredNorm())) continue;
    const double lambda = es.eigenvalues()(i).real();
    if (lambda < best) best = lambda, u = e / std::sqrt(pratt), found = true;
  }
  if (!found) return false;
  sphere->u0 = u(0), sphere->ul = u.segment<3>(1), sphere->uq = u(4);
  return true;
}

bool projectLocalSphere(const LocalSphere& sphere, const Vec3& y, bool keep_orientation, Vec3* foot,
                        Vec3* normal) {
  // Along the gradient line through y (it passes the centre), stable root so that uq -> 0 reduces to the
  // plane projection t = -s / |g|^2.
  const Vec3 g = sphere.ul + 2 * sphere.uq * y;
  const double g2 = g.squaredNorm();
  if (!(g2 > 1e-24)) return false;
  const double sy = sphere.u0 + sphere.ul.dot(y) + sphere.uq * y.squaredNorm();
  const double disc = 1 - 4 * sphere.uq * sy / g2;
  if (!(disc >= 0)) return false;
  const double t = -2 * sy / (g2 * (1 + std::sqrt(disc)));
  *foot = y + t * g;
  Vec3 grad = sphere.ul + 2 * sphere.uq * *foot;
  if (!(grad.squaredNorm() > 0)) return false;
  if (!keep_orientation && grad.dot(g) < 0) grad = -grad;
  *normal = grad.normalized();
  return true;
}

}  // namespace rc
