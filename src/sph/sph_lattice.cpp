#include "relaxed_connectivity/sph/sph_lattice.h"

#include "relaxed_connectivity/mesh/fast_winding_number.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>

#include <Eigen/Dense>

namespace rc {

namespace {

void checkFrame(const SphLattice& lattice, const SphLatticeFrame& frame) {
  const Eigen::Matrix3d& q = frame.orientation;
  if (!q.allFinite() || !frame.origin.allFinite())
    throw std::invalid_argument("SphLatticeFrame: orientation and origin must be finite");
  if ((q.transpose() * q - Eigen::Matrix3d::Identity()).norm() > 1e-9 || q.determinant() < 0.0)
    throw std::invalid_argument("SphLatticeFrame.orientation must be a rotation (orthonormal, det +1)");
  if (lattice.dimension() == 2 && ((q.col(2) - Vec3::UnitZ()).norm() > 1e-12 || q(2, 0) != 0.0 ||
                                   q(2, 1) != 0.0 || frame.origin.z() != 0.0))
    throw std::invalid_argument(
        "SphLatticeFrame: in 2D the orientation must be a rotation about z and origin.z 0");
}

void checkBox(const Vec3& lo, const Vec3& hi, int dimension, const char* who) {
  if (!lo.allFinite() || !hi.allFinite())
    throw std::invalid_argument(std::string(who) + ": box must be finite");
  for (int a = 0; a < dimension; ++a)
    if (!(hi[a] >= lo[a])) throw std::invalid_argument(std::string(who) + ": box is empty (hi < lo)");
}

}  // namespace

SphLattice::SphLattice(int dimension, double spacing) : dimension_(dimension), spacing_(spacing) {
  if (dimension != 2 && dimension != 3)
    throw std::invalid_argument("SphLattice: dimension must be 2 or 3, got " + std::to_string(dimension));
  if (!(spacing > 0.0) || !std::isfinite(spacing))
    throw std::invalid_argument("SphLattice: spacing must be finite and > 0, got " + std::to_string(spacing));
  basis_.col(0) = spacing * Vec3(1.0, 0.0, 0.0);  // (8.20)
  basis_.col(1) = spacing * Vec3(0.5, std::sqrt(0.75), 0.0);
  basis_.col(2) = dimension == 3 ? Vec3(spacing * Vec3(0.5, std::sqrt(1.0 / 12.0), std::sqrt(2.0 / 3.0)))
                                 : Vec3(spacing * Vec3::UnitZ());
  inverse_basis_ = basis_.inverse();
  gram_ = basis_.transpose() * basis_;
  if (dimension == 2) {
    gram_.row(2).setZero();
    gram_.col(2).setZero();
  }
}

Eigen::Vector3i SphLattice::nearestIndex(const Vec3& q_in) const {
  Vec3 q = q_in;
  if (dimension_ == 2) q.z() = 0.0;
  const Vec3 c = inverse_basis_ * q;
  const Eigen::Vector3i base(static_cast<int>(std::lround(c.x())), static_cast<int>(std::lround(c.y())),
                             dimension_ == 3 ? static_cast<int>(std::lround(c.z())) : 0);
  // Fast path: the Voronoi cell of every lattice point contains the ball of radius d/2 around it.
  const double base_d2 = (point(base) - q).squaredNorm();
  if (base_d2 < 0.25 * spacing_ * spacing_) return base;
  Eigen::Vector3i best = base;
  double best_d2 = base_d2;
  const int kz = dimension_ == 3 ? 1 : 0;
  for (int dk = -kz; dk <= kz; ++dk)
    for (int dj = -1; dj <= 1; ++dj)
      for (int di = -1; di <= 1; ++di) {
        const Eigen::Vector3i n = base + Eigen::Vector3i(di, dj, dk);
        const double d2 = (point(n) - q).squaredNorm();
        if (d2 < best_d2) {
          best_d2 = d2;
          best = n;
        }
      }
  return best;
}

double SphLattice::cellVolume() const {
  const double d = spacing_;
  return dimension_ == 3 ? d * d * d / std::sqrt(2.0) : std::sqrt(0.75) * d * d;
}

double SphLattice::particleMass(const SphKernels& kernels, double rest_density) const {
  if (kernels.dimension != dimension_)
    throw std::invalid_argument("SphLattice::particleMass: kernel dimension differs from the lattice's");
  if (!(rest_density > 0.0) || !std::isfinite(rest_density))
    throw std::invalid_argument("SphLattice::particleMass: rest_density must be finite and > 0");
  const int r = static_cast<int>(std::ceil(kernels.h / spacing_ * 1.2)) + 1;
  const int rz = dimension_ == 3 ? r : 0;
  double sum = 0.0;
  for (int k = -rz; k <= rz; ++k)
    for (int j = -r; j <= r; ++j)
      for (int i = -r; i <= r; ++i) sum += kernels.poly6(point(Eigen::Vector3i(i, j, k)).squaredNorm());
  return rest_density / sum;
}

std::vector<Vec3> sampleLattice(const SphLattice& lattice, const SphLatticeFrame& frame, const Vec3& lo,
                                const Vec3& hi, const std::function<bool(const Vec3&)>& inside) {
  const int dim = lattice.dimension();
  checkBox(lo, hi, dim, "sampleLattice");
  checkFrame(lattice, frame);
  // Index range covering the box: map its corners to lattice coordinates.
  const Eigen::Matrix3d to_index = lattice.basis().inverse() * frame.orientation.transpose();
  Vec3 cmin = Vec3::Constant(std::numeric_limits<double>::infinity()), cmax = -cmin;
  for (int corner = 0; corner < 8; ++corner) {
    Vec3 x((corner & 1) ? hi.x() : lo.x(), (corner & 2) ? hi.y() : lo.y(), (corner & 4) ? hi.z() : lo.z());
    if (dim == 2) x.z() = 0.0;
    const Vec3 c = to_index * (x - frame.origin);
    cmin = cmin.cwiseMin(c);
    cmax = cmax.cwiseMax(c);
  }
  Eigen::Vector3i nlo, nhi;
  for (int a = 0; a < 3; ++a) {
    nlo[a] = static_cast<int>(std::floor(cmin[a])) - 1;
    nhi[a] = static_cast<int>(std::ceil(cmax[a])) + 1;
  }
  if (dim == 2) nlo.z() = nhi.z() = 0;
  const double candidates = double(nhi.x() - nlo.x() + 1) * (nhi.y() - nlo.y() + 1) * (nhi.z() - nlo.z() + 1);
  if (candidates > 5e7)
    throw std::invalid_argument("sampleLattice: box needs " + std::to_string(candidates) +
                                " lattice candidates (> 5e7); increase the spacing");
  const double tol = 1e-9 * lattice.spacing();
  std::vector<Vec3> points;
  for (int k = nlo.z(); k <= nhi.z(); ++k)
    for (int j = nlo.y(); j <= nhi.y(); ++j)
      for (int i = nlo.x(); i <= nhi.x(); ++i) {
        const Vec3 x = frame.origin + frame.orientation * lattice.point(Eigen::Vector3i(i, j, k));
        bool in_box = true;
        for (int a = 0; a < dim; ++a) in_box = in_box && x[a] >= lo[a] - tol && x[a] <= hi[a] + tol;
        if (in_box) points.push_back(x);
      }
  std::vector<uint8_t> keep(points.size());
#pragma omp parallel for schedule(dynamic, 64)
  for (long p = 0; p < static_cast<long>(points.size()); ++p) keep[p] = inside(points[p]) ? 1 : 0;
  size_t out = 0;
  for (size_t p = 0; p < points.size(); ++p)
    if (keep[p]) points[out++] = points[p];
  points.resize(out);
  return points;
}

std::vector<Vec3> sampleLatticeBox(const SphLattice& lattice, const Vec3& lo, const Vec3& hi) {
  SphLatticeFrame frame;
  frame.origin = lo;
  if (lattice.dimension() == 2) frame.origin.z() = 0.0;
  return sampleLatticeBox(lattice, lo, hi, frame);
}

std::vector<Vec3> sampleLatticeBox(const SphLattice& lattice, const Vec3& lo, const Vec3& hi,
                                   const SphLatticeFrame& frame) {
  return sampleLattice(lattice, frame, lo, hi, [](const Vec3&) { return true; });
}

std::vector<Vec3> sampleLatticeSphere(const SphLattice& lattice, const Vec3& center, double radius) {
  SphLatticeFrame frame;
  frame.origin = center;
  if (lattice.dimension() == 2) frame.origin.z() = 0.0;
  return sampleLatticeSphere(lattice, center, radius, frame);
}

std::vector<Vec3> sampleLatticeSphere(const SphLattice& lattice, const Vec3& center, double radius,
                                      const SphLatticeFrame& frame) {
  if (!(radius > 0.0) || !std::isfinite(radius))
    throw std::invalid_argument("sampleLatticeSphere: radius must be finite and > 0, got " +
                                std::to_string(radius));
  if (!center.allFinite()) throw std::invalid_argument("sampleLatticeSphere: center must be finite");
  const double r2 = radius * radius * (1.0 + 1e-12);
  Vec3 c = center;
  if (lattice.dimension() == 2) c.z() = 0.0;
  return sampleLattice(lattice, frame, c - Vec3::Constant(radius), c + Vec3::Constant(radius),
                       [&](const Vec3& x) { return (x - c).squaredNorm() <= r2; });
}

double meshWindingNumber(const TriangleMesh& mesh, const Vec3& p) {
  const std::vector<Vec3>& v = mesh.vertices.positions;
  double total = 0.0;
  for (const Triangle& t : mesh.triangles) {
    const Vec3 a = v[t[0]] - p, b = v[t[1]] - p, c = v[t[2]] - p;
    const double la = a.norm(), lb = b.norm(), lc = c.norm();
    const double num = a.dot(b.cross(c));
    const double den = la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb;
    total += 2.0 * std::atan2(num, den);  // solid angle (van Oosterom & Strackee)
  }
  return total / (4.0 * M_PI);
}

std::vector<Vec3> sampleLatticeMesh(const SphLattice& lattice, const TriangleMesh& mesh) {
  SphLatticeFrame frame;
  if (!mesh.vertices.positions.empty()) {
    Vec3 lo = mesh.vertices.positions[0];
    for (const Vec3& x : mesh.vertices.positions) lo = lo.cwiseMin(x);
    frame.origin = lo;
  }
  return sampleLatticeMesh(lattice, mesh, frame);
}

std::vector<Vec3> sampleLatticeMesh(const SphLattice& lattice, const TriangleMesh& mesh,
                                    const SphLatticeFrame& frame) {
  if (lattice.dimension() != 3) throw std::invalid_argument("sampleLatticeMesh: needs a 3D lattice");
  const std::vector<Vec3>& v = mesh.vertices.positions;
  if (v.empty() || mesh.triangles.empty()) throw std::invalid_argument("sampleLatticeMesh: mesh is empty");
  for (size_t i = 0; i < v.size(); ++i)
    if (!v[i].allFinite())
      throw std::invalid_argument("sampleLatticeMesh: vertex " + std::to_string(i) + " is not finite");
  // Closed and consistently oriented: every directed edge once, and its reverse once.
  std::vector<uint64_t> edges;
  edges.reserve(3 * mesh.triangles.size());
  for (size_t f = 0; f < mesh.triangles.size(); ++f) {
    const Triangle& t = mesh.triangles[f];
    for (int e = 0; e < 3; ++e) {
      const uint32_t a = t[e], b = t[(e + 1) % 3];
      if (a >= v.size() || b >= v.size())
        throw std::invalid_argument("sampleLatticeMesh: triangle " + std::to_string(f) +
                                    " has a vertex index out of range");
      edges.push_back((uint64_t(a) << 32) | b);
    }
  }
  std::sort(edges.begin(), edges.end());
  for (size_t e = 0; e < edges.size(); ++e) {
    const uint64_t reverse = (edges[e] << 32) | (edges[e] >> 32);
    if ((e + 1 < edges.size() && edges[e + 1] == edges[e]) ||
        !std::binary_search(edges.begin(), edges.end(), reverse))
      throw std::invalid_argument("sampleLatticeMesh: mesh is not closed and consistently oriented (edge " +
                                  std::to_string(edges[e] >> 32) + "-" +
                                  std::to_string(edges[e] & 0xffffffffu) + ")");
  }
  Vec3 lo = v[0], hi = v[0];
  for (const Vec3& x : v) {
    lo = lo.cwiseMin(x);
    hi = hi.cwiseMax(x);
  }
  const FastWindingNumber winding(mesh);
  return sampleLattice(lattice, frame, lo, hi, [&](const Vec3& x) { return std::abs(winding(x)) > 0.5; });
}

}  // namespace rc
