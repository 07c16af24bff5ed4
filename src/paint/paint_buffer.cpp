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
  if (layer == kBrush && weight_[kSurface].size() != n)
    throw std::logic_error(
        "PaintBuffer::splat: splat the surface before the brush (the depth test needs it)");
  pixel_[layer].assign(n, PaintState());
  weight_[layer].assign(n, 0.0);
  height_sum_[layer].assign(n, 0.0);
  contributed_[layer].assign(n, 0.0);
  shares_[layer].clear();
  sample_volume_[layer].assign(samples.size(), 0.0);
  rate_sum_[layer].assign(n, 0.0);
  rate_weight_[layer].assign(n, 0.0);
  if (layer == kSurface) {
    normal_sum_.assign(n, Vec3::Zero());
    dry_.assign(n, PaintState());
    penetrated_.assign(n, 0);
    pressure_.assign(n, 0.0);
  }

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
      if (layer == kSurface) {
        normal_sum_[p] += w * s.normal.normalized();
        PaintState& d = dry_[p];
        d.dry = PaintColour::mix(d.dry, weight_[layer][p], s.paint.dry, w);
        d.dry_volume = (d.dry_volume * weight_[layer][p] + s.paint.dry_volume * w) / (weight_[layer][p] + w);
      }
      height_sum_[layer][p] += w * h;
      weight_[layer][p] += w;
      if (s.paint.transfer_rate >= 0)
        rate_sum_[layer][p] += w * s.paint.transfer_rate, rate_weight_[layer][p] += w;
      total += w;
    });
    if (!(total > 0)) continue;
    for (Share& share : footprint) share.weight /= total;
    const double volume = s.paint.wet_volume;
    sample_volume_[layer][i] = volume;
    for (const Share& share : footprint) {
      const double v = share.weight * volume;
      addWetPaint(pixel_[layer][share.pixel], s.paint, v);
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
      penetrated_[index(x, y)] = 1;
      pressure_[index(x, y)] = pressure_per_depth * depth;
      PaintState& brush = pixel_[kBrush][index(x, y)];
      PaintState& surface = pixel_[kSurface][index(x, y)];
      const double surface_before = surface.wet_volume, brush_before = brush.wet_volume;
      const size_t p = index(x, y);
      const auto rate = [&](Layer layer, double unset) {
        return rate_weight_[layer][p] > 0 ? rate_sum_[layer][p] / rate_weight_[layer][p] : unset;
      };
      exchangePaint(brush, surface, rate(kBrush, tau_brush_to_surface), rate(kSurface, tau_surface_to_brush),
                    pressure_[p], dt);
      stats.moved_to_surface += std::max(0.0, surface.wet_volume - surface_before);
      stats.moved_to_brush += std::max(0.0, brush.wet_volume - brush_before);
    }
  return stats;
}

template <class Take>
void PaintBuffer::forEachPart(Layer layer, Take&& take) const {
  for (const Share& share : shares_[layer]) {
    // The sample's part of the pixel: its share of the volume the pixel received, or of the footprint
    // weights where the pixel received no volume.
    const double from = contributed_[layer][share.pixel];
    const double part = from > 0 ? share.weight * sample_volume_[layer][share.sample] / from
                                 : share.raw_weight / weight_[layer][share.pixel];
    take(share.sample, share.pixel, part * pixel_[layer][share.pixel].wet_volume);
  }
}

namespace {

/// Wet paint received in parts (a sample's take from the pixels): mixed by (5.11), written to the sample
/// only if it took part.
struct Received {
  PaintState paint = PaintState{PaintColour(), PaintColour(), 0.0, 0.0, 1.0};
  bool touched = false;
  void add(const PaintState& px, double v) {
    addWetPaint(paint, px, v);
    touched = true;
  }
  void writeTo(PaintState& s) const {
    if (!touched) return;
    s.wet_volume = paint.wet_volume;
    if (paint.wet_volume > 0) s.wet = paint.wet, s.optical_density = paint.optical_density;
  }
};

}  // namespace

void PaintBuffer::gather(Layer layer, std::vector<PaintState>& states) const {
  if (states.size() != sample_volume_[layer].size())
    throw std::invalid_argument("PaintBuffer::gather: " + std::to_string(states.size()) + " states for " +
                                std::to_string(sample_volume_[layer].size()) + " splatted samples");
  std::vector<Received> received(states.size());
  forEachPart(layer, [&](uint32_t i, uint32_t p, double v) { received[i].add(pixel_[layer][p], v); });
  for (size_t i = 0; i < states.size(); ++i) received[i].writeTo(states[i]);
}

std::vector<uint8_t> PaintBuffer::penetratedSurfaceSamples() const {
  std::vector<uint8_t> out(sample_volume_[kSurface].size(), 0);
  for (const Share& share : shares_[kSurface])
    if (penetrated_[share.pixel]) out[share.sample] = 1;
  return out;
}

void PaintBuffer::resample(const std::vector<uint8_t>& replace, std::vector<PaintState>& states,
                           std::vector<PixelSurfel>& surfels) const {
  if (states.size() != sample_volume_[kSurface].size() || replace.size() != states.size())
    throw std::invalid_argument("PaintBuffer::resample: " + std::to_string(states.size()) + " states and " +
                                std::to_string(replace.size()) + " flags for " +
                                std::to_string(sample_volume_[kSurface].size()) + " splatted samples");
  std::vector<Received> received(states.size());
  std::vector<Received> at_pixel(pixel_[kSurface].size());
  forEachPart(kSurface, [&](uint32_t i, uint32_t p, double v) {
    (replace[i] ? at_pixel[p] : received[i]).add(pixel_[kSurface][p], v);
  });
  for (size_t i = 0; i < states.size(); ++i)
    if (!replace[i]) received[i].writeTo(states[i]);
  surfels.clear();
  for (int y = 0; y < height_; ++y)
    for (int x = 0; x < width_; ++x) {
      const size_t p = index(x, y);
      if (!at_pixel[p].touched) continue;
      PixelSurfel s;
      s.x = x, s.y = y;
      s.position = pixelCentre(x, y) + height(kSurface, x, y) * normal_;
      s.normal = normal_sum_[p].norm() > 0 ? Vec3(normal_sum_[p].normalized()) : normal_;
      s.radius = pixel_size_;
      s.pressure = pressure_.empty() ? 0.0 : pressure_[p];
      s.paint = dry_[p];
      s.paint.wet_volume = 0;
      s.paint.transfer_rate =
          rate_weight_[kSurface][p] > 0 ? rate_sum_[kSurface][p] / rate_weight_[kSurface][p] : -1.0;
      at_pixel[p].writeTo(s.paint);
      surfels.push_back(s);
    }
}

}  // namespace rc
