// Closest-sphere-packing lattices for sampling elastic solids (thesis 8.2.1): cubic closest packed (fcc)
// in 3D (8.20), hexagonal in 2D.
#pragma once

#include <cmath>
#include <functional>
#include <vector>

#include <Eigen/Core>

#include "relaxed_connectivity/core/surfel_cloud.h"
#include "relaxed_connectivity/core/triangle_mesh.h"
#include "relaxed_connectivity/sph/sph_kernels.h"

namespace rc {

/// The lattice L of (8.20) around the origin with spacing d: points B n for integer n, where the columns of B
/// are d e1, d (e1/2 + sqrt(3/4) e2), d (e1/2 + sqrt(1/12) e2 + sqrt(2/3) e3). In 2D only the first two
/// columns are used (n.z = 0, the hexagonal lattice in the x-y plane). Every point has 12 (2D: 6) nearest
/// neighbours at distance d.
class SphLattice {
 public:
  /// Throws std::invalid_argument unless dimension is 2 or 3 and spacing is finite and > 0.
  SphLattice(int dimension, double spacing);

  int dimension() const { return dimension_; }
  double spacing() const { return spacing_; }
  /// B (columns are the lattice vectors; in 2D the third column is d e3 and unused).
  const Eigen::Matrix3d& basis() const { return basis_; }
  /// B n (n.z ignored in 2D).
  Vec3 point(const Eigen::Vector3i& index) const {
    Vec3 p = basis_.col(0) * index.x() + basis_.col(1) * index.y();
    if (dimension_ == 3) p += basis_.col(2) * index.z();
    return p;
  }
  /// Index of the lattice point nearest to q (Babai rounding refined over the 27 (2D: 9) neighbouring
  /// indices; exact for this reduced basis). z of q is ignored in 2D.
  Eigen::Vector3i nearestIndex(const Vec3& q) const;
  /// The same search from lattice coordinates c = B^-1 q (c.z ignored in 2D; |c| < 2^30); *sq_dist receives
  /// |B n - q|^2. Inline: it runs for every neighbour of every solid particle at every evaluation (8.21).
  Eigen::Vector3i nearestIndexOfCoordinates(const Vec3& c, double* sq_dist) const {
    // Rounding half away from zero (as std::lround) by truncation; copysign keeps it free of branches.
    const auto round = [](double x) { return static_cast<int>(x + std::copysign(0.5, x)); };
    const bool three = dimension_ == 3;
    const int nx = round(c.x()), ny = round(c.y()), nz = three ? round(c.z()) : 0;
    const double ex = c.x() - nx, ey = c.y() - ny, ez = three ? c.z() - nz : 0.0;
    const Eigen::Matrix3d& g = gram_;
    // |B e|^2 = e^T B^T B e.
    const auto norm2 = [&g](double x, double y, double z) {
      return g(0, 0) * x * x + g(1, 1) * y * y + g(2, 2) * z * z +
             2.0 * (g(0, 1) * x * y + g(0, 2) * x * z + g(1, 2) * y * z);
    };
    Eigen::Vector3i best(nx, ny, nz);
    double best_d2 = norm2(ex, ey, ez);
    // Fast path: the Voronoi cell of every lattice point contains the ball of radius d/2 around it.
    if (best_d2 >= 0.25 * spacing_ * spacing_) {
      const int kz = three ? 1 : 0;
      for (int dk = -kz; dk <= kz; ++dk)
        for (int dj = -1; dj <= 1; ++dj)
          for (int di = -1; di <= 1; ++di) {
            const double d2 = norm2(ex - di, ey - dj, ez - dk);
            if (d2 < best_d2) {
              best_d2 = d2;
              best = Eigen::Vector3i(nx + di, ny + dj, nz + dk);
            }
          }
    }
    *sq_dist = best_d2;
    return best;
  }
  /// B^-1.
  const Eigen::Matrix3d& inverseBasis() const { return inverse_basis_; }
  /// Volume (area in 2D) per lattice point: d^3 / sqrt(2) (2D: sqrt(3)/2 d^2).
  double cellVolume() const;
  /// Particle mass that gives a lattice point with full kernel support the rest density under the poly6
  /// density sum (8.4), self included. Throws std::invalid_argument for a bad rest density or a kernel of
  /// another dimension.
  double particleMass(const SphKernels& kernels, double rest_density) const;

 private:
  int dimension_;
  double spacing_;
  Eigen::Matrix3d basis_, inverse_basis_, gram_;  // gram_ = B^T B (2D: the x-y block)
};

/// Placement of a lattice in the world: x = origin + orientation * B n (orientation a rotation; in 2D a
/// rotation about z).
struct SphLatticeFrame {
  Eigen::Matrix3d orientation = Eigen::Matrix3d::Identity();
  Vec3 origin = Vec3::Zero();
};

/// World positions of the lattice points inside the box [lo, hi] (bounds of the search) for which
/// `inside` holds, in increasing (k, j, i) order. Throws std::invalid_argument for an empty or non-finite
/// box, a frame that is not a rotation (or not about z in 2D), or more than 50 million candidates.
std::vector<Vec3> sampleLattice(const SphLattice& lattice, const SphLatticeFrame& frame, const Vec3& lo,
                                const Vec3& hi, const std::function<bool(const Vec3&)>& inside);

/// Lattice points in the closed box [lo, hi] (2D: z ignored). Default frame: origin at lo, axis aligned.
std::vector<Vec3> sampleLatticeBox(const SphLattice& lattice, const Vec3& lo, const Vec3& hi);
std::vector<Vec3> sampleLatticeBox(const SphLattice& lattice, const Vec3& lo, const Vec3& hi,
                                   const SphLatticeFrame& frame);

/// Lattice points in the closed ball (2D: disc) of `radius` around `center`. Default frame: origin at the
/// centre. Throws std::invalid_argument for a radius not finite and > 0.
std::vector<Vec3> sampleLatticeSphere(const SphLattice& lattice, const Vec3& center, double radius);
std::vector<Vec3> sampleLatticeSphere(const SphLattice& lattice, const Vec3& center, double radius,
                                      const SphLatticeFrame& frame);

/// Generalised winding number of a closed triangle mesh at p (1 inside, 0 outside; solid angles by van
/// Oosterom & Strackee).
double meshWindingNumber(const TriangleMesh& mesh, const Vec3& p);

/// Lattice points inside a closed, consistently oriented triangle mesh (|winding number| > 1/2), 3D only.
/// Default frame: origin at the minimum corner of the mesh bounds. Throws std::invalid_argument for a 2D
/// lattice, an empty mesh, a vertex index out of range, a non-finite vertex, or a mesh that is not closed
/// (an edge not shared by exactly one oppositely oriented triangle).
std::vector<Vec3> sampleLatticeMesh(const SphLattice& lattice, const TriangleMesh& mesh);
std::vector<Vec3> sampleLatticeMesh(const SphLattice& lattice, const TriangleMesh& mesh,
                                    const SphLatticeFrame& frame);

}  // namespace rc
