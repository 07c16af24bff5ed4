#include "relaxed_connectivity/render/csg/patch_sampling.h"

#include <Eigen/SVD>
#include <cmath>
#include <stdexcept>
#include <string>

namespace rc {

namespace {

constexpr double kGoldenAngle = 2.39996322972865332;  // pi (3 - sqrt(5))
/// Covering radius of a Fibonacci lattice relative to sqrt(area per sample): a regular hexagonal cell has
/// 0.62; the lattice's cells are less regular, so a conservative 0.8.
constexpr double kFibonacciCoverFactor = 0.8;

void requireSamples(const PatchSampling& sampling, const char* what) {
  if (sampling.samples == 0 && !(sampling.spacing > 0))
    throw std::invalid_argument(std::string(what) + ": samples or spacing must be positive");
  if (!(sampling.radius_scale > 0))
    throw std::invalid_argument(std::string(what) + ": radius_scale must be positive");
}

/// Unit-sphere Fibonacci point i of n.
Vec3 fibonacciPoint(size_t i, size_t n) {
  const double z = 1.0 - (2.0 * i + 1.0) / n;
  const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
  const double phi = kGoldenAngle * i;
  return Vec3(r * std::cos(phi), r * std::sin(phi), z);
}

/// Rectangle c + a e1 + b e2, |a| <= half_a, |b| <= half_b, on an ma x mb grid of cell centres.
void appendRectangleGrid(const Vec3& center, const Vec3& normal, const Vec3& e1, const Vec3& e2,
                         double half_a, double half_b, size_t ma, size_t mb, double radius_scale,
                         SurfelCloud* out) {
  const double ca = 2 * half_a / ma, cb = 2 * half_b / mb;
  const double radius = radius_scale * 0.5 * std::sqrt(ca * ca + cb * cb);  // half the cell diagonal
  for (size_t j = 0; j < mb; ++j) {
    for (size_t i = 0; i < ma; ++i) {
      const double a = -half_a + (i + 0.5) * ca, b = -half_b + (j + 0.5) * cb;
      out->positions.push_back(center + a * e1 + b * e2);
      out->normals.push_back(normal);
      out->radii.push_back(radius);
    }
  }
}

}  // namespace

size_t PatchSampling::countFor(double area) const {
  if (spacing > 0) return std::max<size_t>(1, size_t(std::ceil(area / (spacing * spacing))));
  return samples;
}

Vec3 anyOrthogonal(const Vec3& n) {
  const Vec3 other = std::abs(n.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
  return n.cross(other).normalized();
}

SurfelCloud sampleSphere(const Vec3& center, double radius, const PatchSampling& sampling) {
  requireSamples(sampling, "sampleSphere");
  if (!(radius > 0)) throw std::invalid_argument("sampleSphere: radius must be positive");
  const size_t n = sampling.countFor(4 * M_PI * radius * radius);
  const double cover = kFibonacciCoverFactor * radius * std::sqrt(4 * M_PI / n);
  SurfelCloud cloud;
  cloud.positions.resize(n);
  cloud.normals.resize(n);
  cloud.radii.assign(n, sampling.radius_scale * cover);
  for (size_t i = 0; i < n; ++i) {
    const Vec3 u = fibonacciPoint(i, n);
    cloud.positions[i] = center + radius * u;
    cloud.normals[i] = u;
  }
  return cloud;
}

SurfelCloud sampleEllipsoid(const Vec3& center, const Vec3& semi_axes, const Eigen::Matrix3d& rotation,
                            const PatchSampling& sampling) {
  requireSamples(sampling, "sampleEllipsoid");
  if (!(semi_axes.minCoeff() > 0)) throw std::invalid_argument("sampleEllipsoid: semi-axes must be positive");
  // Knud Thomsen's area approximation (relative error < 1.1%).
  const double p = 1.6075, ap = std::pow(semi_axes.x(), p), bp = std::pow(semi_axes.y(), p),
               cp = std::pow(semi_axes.z(), p);
  const size_t n = sampling.countFor(4 * M_PI * std::pow((ap * bp + ap * cp + bp * cp) / 3, 1 / p));
  const double disk = sampling.radius_scale * kFibonacciCoverFactor * std::sqrt(4 * M_PI / n);
  const Eigen::Matrix3d linear = rotation * semi_axes.asDiagonal();
  SurfelCloud cloud;
  cloud.positions.resize(n);
  cloud.normals.resize(n);
  cloud.radii.resize(n);
  cloud.axes1.resize(n);
  cloud.axes2.resize(n);
  for (size_t i = 0; i < n; ++i) {
    const Vec3 u = fibonacciPoint(i, n);
    cloud.positions[i] = center + linear * u;
    cloud.normals[i] = (rotation * u.cwiseQuotient(semi_axes)).normalized();  // gradient of |x/a|^2
    // The sphere's covering disk in the tangent plane at u, mapped through the ellipsoid: an ellipse whose
    // principal axes are the SVD of the 3x2 image of the tangent basis.
    const Vec3 t1 = anyOrthogonal(u), t2 = u.cross(t1);
    Eigen::Matrix<double, 3, 2> image;
    image.col(0) = linear * t1 * disk;
    image.col(1) = linear * t2 * disk;
    const Eigen::JacobiSVD<Eigen::Matrix<double, 3, 2>> svd(image, Eigen::ComputeThinU);
    cloud.axes1[i] = svd.matrixU().col(0) * svd.singularValues()(0);
    cloud.axes2[i] = svd.matrixU().col(1) * svd.singularValues()(1);
    cloud.radii[i] = svd.singularValues()(0);
  }
  return cloud;
}

SurfelCloud samplePlaneSquare(const Vec3& center, const Vec3& normal, const Vec3& up, double size,
                              const PatchSampling& sampling) {
  requireSamples(sampling, "samplePlaneSquare");
  if (!(size > 0)) throw std::invalid_argument("samplePlaneSquare: size must be positive");
  if (!(normal.norm() > 0)) throw std::invalid_argument("samplePlaneSquare: normal must be non-zero");
  const Vec3 n = normal.normalized();
  Vec3 e1 = up - up.dot(n) * n;
  e1 = e1.norm() > 1e-9 ? e1.normalized() : anyOrthogonal(n);
  const Vec3 e2 = n.cross(e1);
  const size_t m =
      std::max<size_t>(1, size_t(std::lround(std::sqrt(double(sampling.countFor(size * size))))));
  SurfelCloud cloud;
  appendRectangleGrid(center, n, e1, e2, 0.5 * size, 0.5 * size, m, m, sampling.radius_scale, &cloud);
  return cloud;
}

SurfelCloud samplePlaneDisk(const Vec3& center, const Vec3& normal, double radius) {
  if (!(radius > 0)) throw std::invalid_argument("samplePlaneDisk: radius must be positive");
  if (!(normal.norm() > 0)) throw std::invalid_argument("samplePlaneDisk: normal must be non-zero");
  SurfelCloud cloud;
  cloud.positions = {center};
  cloud.normals = {normal.normalized()};
  cloud.radii = {radius};
  return cloud;
}

SurfelCloud sampleBoxFaces(const Vec3& center, const Vec3& half_extents, const Eigen::Matrix3d& rotation,
                           const PatchSampling& sampling) {
  requireSamples(sampling, "sampleBoxFaces");
  if (!(half_extents.minCoeff() > 0))
    throw std::invalid_argument("sampleBoxFaces: half extents must be positive");
  SurfelCloud cloud;
  for (int axis = 0; axis < 3; ++axis) {
    const int a = (axis + 1) % 3, b = (axis + 2) % 3;
    const double ha = half_extents[a], hb = half_extents[b];
    const double cell = sampling.spacing > 0 ? sampling.spacing : std::sqrt(4 * ha * hb / sampling.samples);
    const size_t ma = std::max<size_t>(1, size_t(std::lround(2 * ha / cell)));
    const size_t mb = std::max<size_t>(1, size_t(std::lround(2 * hb / cell)));
    for (int sign : {1, -1}) {
      const Vec3 n = sign * rotation.col(axis);
      appendRectangleGrid(center + half_extents[axis] * n, n, rotation.col(a), rotation.col(b), ha, hb, ma,
                          mb, sampling.radius_scale, &cloud);
    }
  }
  return cloud;
}

}  // namespace rc
