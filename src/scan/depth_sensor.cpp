#include "relaxed_connectivity/scan/depth_sensor.h"

#include <cmath>
#include <limits>
#include <stdexcept>

namespace rc {

namespace {

constexpr double kPi = 3.14159265358979323846;

[[noreturn]] void fail(const std::string& field, const std::string& problem) {
  throw std::invalid_argument("DepthSensorConfig: " + field + " " + problem);
}

void requireFinite(const char* field, double value) {
  if (!std::isfinite(value)) fail(field, "must be finite, got " + std::to_string(value));
}

uint64_t splitMix64(uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

// Counter-based random stream of one pixel: reproducible whatever thread renders the pixel.
class PixelRandom {
 public:
  PixelRandom(uint64_t seed, uint64_t frame, uint64_t pixel)
      : state_(splitMix64(seed ^ splitMix64(frame ^ splitMix64(pixel + 0x632BE59BD9B4E019ull)))) {}
  double uniform() {  // in (0, 1)
    state_ = splitMix64(state_);
    return ((state_ >> 11) + 0.5) * (1.0 / 9007199254740992.0);
  }
  double gaussian() {  // Box-Muller
    const double r = std::sqrt(-2.0 * std::log(uniform()));
    return r * std::cos(2.0 * kPi * uniform());
  }

 private:
  uint64_t state_;
};

uint8_t mixChannel(const Rgba& a, const Rgba& b, const Rgba& c, double wa, double wb, double wc, int k) {
  const double x = wa * a[k] + wb * b[k] + wc * c[k];
  return static_cast<uint8_t>(std::min(255.0, std::max(0.0, x)) + 0.5);
}

}  // namespace

PinholeIntrinsics PinholeIntrinsics::fromHorizontalFov(uint32_t width, uint32_t height,
                                                       double horizontal_fov) {
  if (!(horizontal_fov > 0.0 && horizontal_fov < kPi))
    throw std::invalid_argument(
        "PinholeIntrinsics::fromHorizontalFov: horizontal_fov must be in (0, pi) radians, got " +
        std::to_string(horizontal_fov));
  PinholeIntrinsics k;
  k.width = width;
  k.height = height;
  k.fx = k.fy = 0.5 * width / std::tan(0.5 * horizontal_fov);
  k.cx = 0.5 * (static_cast<double>(width) - 1.0);
  k.cy = 0.5 * (static_cast<double>(height) - 1.0);
  k.validate();
  return k;
}

void PinholeIntrinsics::validate() const {
  if (width == 0) fail("intrinsics.width", "must be > 0, got 0");
  if (height == 0) fail("intrinsics.height", "must be > 0, got 0");
  if (static_cast<uint64_t>(width) * height > (1ull << 31))
    fail("intrinsics.width * height",
         "is too large (" + std::to_string(uint64_t(width) * height) + " pixels)");
  if (!(fx > 0.0) || !std::isfinite(fx))
    fail("intrinsics.fx", "must be positive and finite, got " + std::to_string(fx));
  if (!(fy > 0.0) || !std::isfinite(fy))
    fail("intrinsics.fy", "must be positive and finite, got " + std::to_string(fy));
  requireFinite("intrinsics.cx", cx);
  requireFinite("intrinsics.cy", cy);
}

void DepthSensorConfig::validate() const {
  intrinsics.validate();
  requireFinite("min_range", min_range);
  requireFinite("max_range", max_range);
  if (min_range < 0.0) fail("min_range", "must be >= 0, got " + std::to_string(min_range));
  if (!(min_range < max_range))
    fail("min_range", "(" + std::to_string(min_range) + ") must be smaller than max_range (" +
                          std::to_string(max_range) + ")");
  requireFinite("noise.sigma_constant", noise.sigma_constant);
  requireFinite("noise.sigma_quadratic", noise.sigma_quadratic);
  if (noise.sigma_constant < 0.0)
    fail("noise.sigma_constant", "must be >= 0, got " + std::to_string(noise.sigma_constant));
  if (noise.sigma_quadratic < 0.0)
    fail("noise.sigma_quadratic", "must be >= 0, got " + std::to_string(noise.sigma_quadratic));
  if (!(noise.dropout_probability >= 0.0 && noise.dropout_probability <= 1.0))
    fail("noise.dropout_probability", "must be in [0, 1], got " + std::to_string(noise.dropout_probability));
}

DepthSensor::DepthSensor(const DepthSensorConfig& config) : config_(config) {
  config_.validate();
}

Ray DepthSensor::pixelRay(double u, double v, const Eigen::Isometry3d& world_T_sensor) const {
  const PinholeIntrinsics& k = config_.intrinsics;
  Ray ray;
  ray.origin = world_T_sensor.translation();
  ray.direction = world_T_sensor.linear() * Vec3((u - k.cx) / k.fx, (v - k.cy) / k.fy, 1.0);
  return ray;
}

bool DepthSensor::project(const Vec3& p, double* u, double* v) const {
  if (!(p.z() > 0.0)) return false;
  const PinholeIntrinsics& k = config_.intrinsics;
  *u = k.cx + k.fx * p.x() / p.z();
  *v = k.cy + k.fy * p.y() / p.z();
  return true;
}

SurfelCloud DepthSensor::capture(const MeshRayCaster& caster, const Eigen::Isometry3d& world_T_sensor,
                                 uint64_t frame_index) const {
  const PinholeIntrinsics& k = config_.intrinsics;
  const TriangleMesh& mesh = caster.mesh();
  const bool with_colors = mesh.vertices.hasColors() && mesh.vertices.colors.size() == mesh.vertices.size();
  const bool vertex_normals = config_.smooth_normals && mesh.vertices.hasNormals() &&
                              mesh.vertices.normals.size() == mesh.vertices.size();
  const size_t pixels = static_cast<size_t>(k.width) * k.height;
  const double nan = std::numeric_limits<double>::quiet_NaN();

  SurfelCloud cloud;
  cloud.frame_id = config_.frame_id;
  cloud.positions.resize(pixels);
  if (config_.output_normals) cloud.normals.resize(pixels);
  if (with_colors) cloud.colors.resize(pixels);

  const Eigen::Matrix3d rotation = world_T_sensor.linear();
  const Eigen::Matrix3d sensor_R_world = rotation.transpose();
  const Vec3 origin = world_T_sensor.translation();
  const DepthNoise& noise = config_.noise;
  const bool noisy = noise.sigma_constant > 0.0 || noise.sigma_quadratic > 0.0;
  const bool dropout = noise.dropout_probability > 0.0;

#pragma omp parallel for schedule(dynamic, 1)
  for (int64_t row = 0; row < static_cast<int64_t>(k.height); ++row) {
    Ray ray;
    ray.origin = origin;
    ray.t_min = 0.0;  // a surface closer than min_range blocks the view (no return), it is not see-through
    ray.t_max = config_.max_range;
    RayHit hit;
    for (uint32_t col = 0; col < k.width; ++col) {
      const size_t pixel = static_cast<size_t>(row) * k.width + col;
      const Vec3 direction_sensor((col - k.cx) / k.fx, (row - k.cy) / k.fy, 1.0);
      ray.direction = rotation * direction_sensor;
      // t equals the depth z because the optical-axis component of the direction is 1.
      bool valid = caster.intersect(ray, &hit) && hit.t >= config_.min_range;
      double depth = hit.t;
      if (valid && (noisy || dropout)) {
        PixelRandom random(config_.seed, frame_index, pixel);
        if (dropout && random.uniform() < noise.dropout_probability) valid = false;
        if (noisy) depth += noise.sigma(depth) * random.gaussian();
        if (!(depth > 0.0)) valid = false;
      }
      if (!valid) {
        cloud.positions[pixel] = Vec3::Constant(nan);
        if (config_.output_normals) cloud.normals[pixel] = Vec3::Constant(nan);
        if (with_colors) cloud.colors[pixel] = {0, 0, 0, 0};
        continue;
      }
      cloud.positions[pixel] = depth * direction_sensor;
      const Triangle& tri = mesh.triangles[hit.triangle];
      const double w0 = 1.0 - hit.u - hit.v;
      if (config_.output_normals) {
        Vec3 n = hit.normal;
        if (vertex_normals) {
          const auto& vn = mesh.vertices.normals;
          const Vec3 smooth = w0 * vn[tri[0]] + hit.u * vn[tri[1]] + hit.v * vn[tri[2]];
          const double length = smooth.norm();
          if (length > 1e-12) n = smooth / length;
        }
        n = sensor_R_world * n;
        if (n.dot(direction_sensor) > 0.0) n = -n;  // face the sensor
        cloud.normals[pixel] = n;
      }
      if (with_colors) {
        const auto& c = mesh.vertices.colors;
        Rgba& out = cloud.colors[pixel];
        for (int channel = 0; channel < 4; ++channel)
          out[channel] = mixChannel(c[tri[0]], c[tri[1]], c[tri[2]], w0, hit.u, hit.v, channel);
      }
    }
  }

  if (config_.organized) {
    cloud.width = k.width;
    cloud.height = k.height;
  } else {
    cloud.removeNonFinite();
    cloud.width = cloud.height = 0;
  }
  return cloud;
}

}  // namespace rc
