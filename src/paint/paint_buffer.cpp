#include "relaxed_connectivity/paint/paint_buffer.h"

#include <Eigen/Eigenvalues>
#include <cmath>
#include <stdexcept>
#include <string>

#include "relaxed_connectivity/paint/paint_exchange.h"
#include "relaxed_connectivity/render/splat/ewa_splat.h"
#include "relaxed_connectivity/render/splat/splat_rasterizer.h"

namespace rc {

namespace {
constexpr double kCameraHeight = 1.0;  // the orthographic camera sits this far above the plane [m]
}  // namespace

void PaintBuffer::fitPlane(const std::vector<Vec3>& points, const Vec3& up, Vec3* centre, Vec3* normal) {
  if (points.size() < 3) throw std::invalid_argument("PaintBuffer::fitPlane: needs at least 3 points");
  Vec3 mean = Vec3::Zero();
  for (const Vec3& p : points) mean += p;
  mean /= double(points.size());
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  for (const Vec3& p : points) covariance += (p - mean) * (p - mean).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(covariance);
  Vec3 n = eig.eigenvectors().col(0);  // least spread
  if (n.dot(up) < 0) n = -n;
  *centre = mean;
  *normal = n;
}

PaintBuffer::PaintBuffer(const Vec3& centre, const Vec3& normal, double pixel_size, int width, int height)
    : centre_(centre), normal_(normal.normalized()), pixel_size_(pixel_size), width_(width), height_(height) {
  if (!(pixel_size > 0) || !std::isfinite(pixel_size))
    throw std::invalid_argument("PaintBuffer: pixel size must be positive, got " +
                                std::to_string(pixel_size));
  if (width < 1 || height < 1 || width > 4096 || height > 4096)
    throw std::invalid_argument("PaintBuffer: " + std::to_string(width) + " x " + std::to_string(height) +
                                " pixels (1..4096 each)");
  if (!centre.allFinite() || !normal_.allFinite())
    throw std::invalid_argument("PaintBuffer: centre and normal must be finite (and the normal non-zero)");
  axis_u_ = normal_.unitOrthogonal();
  axis_v_ = normal_.cross(axis_u_);
}

Vec3 PaintBuffer::pixelCentre(int x, int y) const {
  // The camera's image x runs along u, its y along -v (x right, y down, z = -normal forward).
  const double cx = 0.5 * (width_ - 1), cy = 0.5 * (height_ - 1);
  return centre_ + (x - cx) * pixel_size_ * axis_u_ - (y - cy) * pixel_size_ * axis_v_;
}

void PaintBuffer::splat(Layer layer, const std::vector<PaintSample>& samples) {
  const size_t n = size_t(width_) * size_t(height_);
  pixel_[layer].assign(n, PaintState());
  weight_[layer].assign(n, 0.0);
  height_sum_[layer].assign(n, 0.0);
  contributed_[layer].assign(n, 0.0);
  shares_[layer].clear();
  sample_volume_[layer].assign(samples.size(), 0.0);

  Camera camera = Camera::orthographic(uint32_t(width_), uint32_t(height_), width_ * pixel_size_);
  Eigen::Matrix3d rotation;
  rotation.col(0) = axis_u_;
  rotation.col(1) = -axis_v_;
  rotation.col(2) = -normal_;
  camera.world_T_camera.linear() = rotation;
  camera.world_T_camera.translation() = centre_ + kCameraHeight * normal_;
  const CameraFrame frame(camera);
  const EwaParams params;
  const splat_tile::TileRect all{0, 0, width_ - 1, height_ - 1};
  // The renderer's Gaussian over the cut-off ellipse (r2 = 1 at the cut-off radius).
  const double cutoff_sigmas = params.cutoff_radius / kKernelSigmaPerRadius;
  std::vector<Share> footprint;
  for (size_t i = 0; i < samples.size(); ++i) {
    const PaintSample& s = samples[i];
    SplatRaster raster;
    const SplatSetup setup = setupCircularEwaSplat(s.position, s.normal, s.radius, frame, params, &raster);
    if (setup == SplatSetup::kCulled || setup == SplatSetup::kInvalid) continue;
    footprint.clear();
    double total = 0;
    splat_tile::rasterizeSplat(raster, all, [&](int x, int y, float r2, float z) {
      const size_t p = index(x, y);
      const double h = kCameraHeight - double(z);
      if (layer == kBrush &&
          !(weight_[kSurface][p] > 0 && h < height_sum_[kSurface][p] / weight_[kSurface][p]))
        return;  // the depth test: only penetrating brush parts take part
      const double w = std::exp(-0.5 * cutoff_sigmas * cutoff_sigmas * double(r2));
      footprint.push_back({uint32_t(i), uint32_t(p), w, w});
      height_sum_[layer][p] += w * h;
      weight_[layer][p] += w;
      total += w;
    });
    if (!(total > 0)) continue;
    for (Share& share : footprint) share.weight /= total;
    const double volume = s.paint.wet_volume;
    sample_volume_[layer][i] = volume;
    for (const Share& share : footprint) {
      PaintState& px = pixel_[layer][share.pixel];
      const double v = share.weight * volume;
      px.wet = PaintColour::mix(px.wet, px.wet_volume, s.paint.wet, v);
      px.optical_density =
          px.wet_volume + v > 0
              ? (px.optical_density * px.wet_volume + s.paint.optical_density * v) / (px.wet_volume + v)
              : s.paint.optical_density;
      px.wet_volume += v;
      contributed_[layer][share.pixel] += v;
      shares_[layer].push_back(share);
    }
  }
}

PaintTransferStats PaintBuffer::transfer(double tau_brush_to_surface, double tau_surface_to_brush,
                                         double pressure_per_depth, double dt) {
  PaintTransferStats stats;
  if (pixel_[kSurface].empty() || pixel_[kBrush].empty()) return stats;
  for (int y = 0; y < height_; ++y)
    for (int x = 0; x < width_; ++x) {
      if (!covered(kSurface, x, y) || !covered(kBrush, x, y)) continue;
      const double depth = height(kSurface, x, y) - height(kBrush, x, y);
      if (!(depth > 0)) continue;
      ++stats.penetrated_pixels;
      PaintState& brush = pixel_[kBrush][index(x, y)];
      PaintState& surface = pixel_[kSurface][index(x, y)];
      const double surface_before = surface.wet_volume, brush_before = brush.wet_volume;
      exchangePaint(brush, surface, tau_brush_to_surface, tau_surface_to_brush, pressure_per_depth * depth,
                    dt);
      stats.moved_to_surface += std::max(0.0, surface.wet_volume - surface_before);
      stats.moved_to_brush += std::max(0.0, brush.wet_volume - brush_before);
    }
  return stats;
}

void PaintBuffer::gather(Layer layer, std::vector<PaintState>& states) const {
  if (states.size() != sample_volume_[layer].size())
    throw std::invalid_argument("PaintBuffer::gather: " + std::to_string(states.size()) + " states for " +
                                std::to_string(sample_volume_[layer].size()) + " splatted samples");
  // Per sample: the volume, colour and density it takes back.
  std::vector<double> volume(states.size(), 0.0), density(states.size(), 0.0);
  std::vector<PaintColour> colour(states.size());
  std::vector<uint8_t> touched(states.size(), 0);
  for (const Share& share : shares_[layer]) {
    const PaintState& px = pixel_[layer][share.pixel];
    const double from = contributed_[layer][share.pixel];
    // The sample's part of the pixel: its share of the volume the pixel received, or of the footprint
    // weights where the pixel received no volume.
    const double part = from > 0 ? share.weight * sample_volume_[layer][share.sample] / from
                                 : share.raw_weight / weight_[layer][share.pixel];
    const double v = part * px.wet_volume;
    const uint32_t i = share.sample;
    colour[i] = PaintColour::mix(colour[i], volume[i], px.wet, v);
    density[i] = volume[i] + v > 0 ? (density[i] * volume[i] + px.optical_density * v) / (volume[i] + v)
                                   : px.optical_density;
    volume[i] += v;
    touched[i] = 1;
  }
  for (size_t i = 0; i < states.size(); ++i) {
    if (!touched[i]) continue;
    states[i].wet_volume = volume[i];
    if (volume[i] > 0) states[i].wet = colour[i], states[i].optical_density = density[i];
  }
}

}  // namespace rc
