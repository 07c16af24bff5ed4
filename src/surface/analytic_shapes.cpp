#include "relaxed_connectivity/surface/analytic_shapes.h"

#include <cmath>
#include <numeric>
#include <random>
#include <stdexcept>

namespace rc {

namespace {

constexpr double kPi = 3.14159265358979323846;
const double kGoldenRatio = (1.0 + std::sqrt(5.0)) / 2.0;

void addNoise(SurfelCloud& cloud, const SamplingOptions& options) {
  if (options.noise_sigma <= 0) return;
  std::mt19937_64 rng(options.seed ^ 0x9e3779b97f4a7c15ULL);
  std::normal_distribution<double> gauss(0.0, options.noise_sigma);
  for (Vec3& p : cloud.positions) p += Vec3(gauss(rng), gauss(rng), gauss(rng));
}

/// First root of an exact signed distance along a ray by sphere tracing (the SDF is 1-Lipschitz).
bool sphereTrace(const AnalyticSurface& s, const Vec3& origin, const Vec3& dir, double t_min, double* t_out) {
  const double len = dir.norm();
  if (!(len > 0)) return false;
  const Vec3 d = dir / len;
  double t = t_min * len;
  const double scale = s.minFeatureSize();
  for (int i = 0; i < 100000; ++i) {
    const double dist = std::abs(s.signedDistance(origin + t * d));
    if (dist < 1e-14 * scale) {
      *t_out = t / len;
      return true;
    }
    t += dist;
    if (t > 1e3 * scale + (origin - s.closestPoint(origin)).norm() * 2) return false;
  }
  return false;
}

}  // namespace

double AnalyticSurface::spacing(size_t n) const {
  return std::sqrt(area() / static_cast<double>(n));
}

// ----------------------------------------------------------------------------------------------------------------
AnalyticSphere::AnalyticSphere(const Vec3& center, double radius) : center_(center), radius_(radius) {
  if (!(radius > 0)) throw std::invalid_argument("AnalyticSphere: radius must be positive");
}

double AnalyticSphere::signedDistance(const Vec3& x) const {
  return (x - center_).norm() - radius_;
}

Vec3 AnalyticSphere::normal(const Vec3& x) const {
  const Vec3 d = x - center_;
  const double n = d.norm();
  return n > 0 ? Vec3(d / n) : Vec3::UnitZ();
}

Vec3 AnalyticSphere::closestPoint(const Vec3& x) const {
  return center_ + radius_ * normal(x);
}

double AnalyticSphere::area() const {
  return 4 * kPi * radius_ * radius_;
}

SurfelCloud AnalyticSphere::sample(size_t n, const SamplingOptions& options) const {
  SurfelCloud cloud;
  cloud.positions.resize(n);
  cloud.normals.resize(n);
  std::mt19937_64 rng(options.seed);
  std::normal_distribution<double> gauss(0.0, 1.0);
  for (size_t i = 0; i < n; ++i) {
    Vec3 dir;
    if (options.pattern == SamplingPattern::kFibonacci) {
      const double z = 1.0 - 2.0 * (static_cast<double>(i) + 0.5) / static_cast<double>(n);
      const double phi = 2 * kPi * std::fmod(static_cast<double>(i) / kGoldenRatio, 1.0);
      const double rho = std::sqrt(std::max(0.0, 1 - z * z));
      dir = Vec3(rho * std::cos(phi), rho * std::sin(phi), z);
    } else {
      do dir = Vec3(gauss(rng), gauss(rng), gauss(rng));
      while (dir.squaredNorm() < 1e-12);
      dir.normalize();
    }
    cloud.normals[i] = dir;
    cloud.positions[i] = center_ + radius_ * dir;
  }
  addNoise(cloud, options);
  return cloud;
}

bool AnalyticSphere::intersectRay(const Vec3& origin, const Vec3& dir, double t_min, double* t) const {
  const Vec3 o = origin - center_;
  const double a = dir.squaredNorm(), b = o.dot(dir), c = o.squaredNorm() - radius_ * radius_;
  const double disc = b * b - a * c;
  if (!(a > 0) || disc < 0) return false;
  const double s = std::sqrt(disc);
  // Stable roots of a t^2 + 2 b t + c = 0.
  const double q = -(b + (b >= 0 ? s : -s));
  double t0 = q / a, t1 = q != 0 ? c / q : t0;
  if (t0 > t1) std::swap(t0, t1);
  if (t0 >= t_min) return *t = t0, true;
  if (t1 >= t_min) return *t = t1, true;
  return false;
}

// ----------------------------------------------------------------------------------------------------------------
AnalyticTorus::AnalyticTorus(const Vec3& center, double major_radius, double minor_radius)
    : center_(center), major_radius_(major_radius), minor_radius_(minor_radius) {
  if (!(minor_radius > 0) || !(major_radius > minor_radius))
    throw std::invalid_argument("AnalyticTorus: need 0 < minor_radius < major_radius");
}

Vec3 AnalyticTorus::tubeCenter(const Vec3& x) const {
  const Vec3 d = x - center_;
  const double rho = std::hypot(d.x(), d.y());
  const Vec3 radial = rho > 0 ? Vec3(d.x() / rho, d.y() / rho, 0) : Vec3::UnitX();
  return center_ + major_radius_ * radial;
}

double AnalyticTorus::signedDistance(const Vec3& x) const {
  return (x - tubeCenter(x)).norm() - minor_radius_;
}

Vec3 AnalyticTorus::normal(const Vec3& x) const {
  const Vec3 c = tubeCenter(x);
  const Vec3 d = x - c;
  const double n = d.norm();
  if (n > 0) return d / n;
  return ((c - center_) / major_radius_).eval();  // on the tube centre circle: any direction; pick outward
}

Vec3 AnalyticTorus::closestPoint(const Vec3& x) const {
  return tubeCenter(x) + minor_radius_ * normal(x);
}

double AnalyticTorus::area() const {
  return 4 * kPi * kPi * major_radius_ * minor_radius_;
}

SurfelCloud AnalyticTorus::sample(size_t n, const SamplingOptions& options) const {
  SurfelCloud cloud;
  cloud.positions.resize(n);
  cloud.normals.resize(n);
  std::mt19937_64 rng(options.seed);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  const double R = major_radius_, r = minor_radius_;
  size_t lattice_step =
      std::max<size_t>(1, static_cast<size_t>(std::llround(static_cast<double>(n) / kGoldenRatio)));
  while (std::gcd(lattice_step, n) != 1) ++lattice_step;
  for (size_t i = 0; i < n; ++i) {
    double u, v;  // u around the z axis, v around the tube; area element (R + r cos v) du dv
    if (options.pattern == SamplingPattern::kFibonacci) {
      // Rank-1 lattice (i/n, i g/n) with g ~ n/phi coprime to n: golden-ratio quasi-uniform and periodic in
      // both parameters, so there is no seam where the lattice ends meet.
      u = 2 * kPi * static_cast<double>((i * lattice_step) % n) / static_cast<double>(n);
      // Invert the cumulative area F(v) = (v + (r/R) sin v) / (2 pi) by Newton's method.
      const double target = 2 * kPi * (static_cast<double>(i) + 0.5) / static_cast<double>(n);
      v = target;
      for (int it = 0; it < 50; ++it) {
        const double f = v + (r / R) * std::sin(v) - target, df = 1 + (r / R) * std::cos(v);
        const double step = f / df;
        v -= step;
        if (std::abs(step) < 1e-15) break;
      }
    } else {
      u = 2 * kPi * uniform(rng);
      do v = 2 * kPi * uniform(rng);
      while (uniform(rng) * (R + r) > R + r * std::cos(v));
    }
    const Vec3 radial(std::cos(u), std::sin(u), 0);
    const Vec3 nrm = std::cos(v) * radial + std::sin(v) * Vec3::UnitZ();
    cloud.normals[i] = nrm;
    cloud.positions[i] = center_ + R * radial + r * nrm;
  }
  addNoise(cloud, options);
  return cloud;
}

bool AnalyticTorus::intersectRay(const Vec3& origin, const Vec3& dir, double t_min, double* t) const {
  return sphereTrace(*this, origin, dir, t_min, t);
}

}  // namespace rc
