// The paint buffer of thesis 5.5 (Fig. 5.6): a pixel grid in the least-squares plane around the brush tip.
// Object surfels and brush surfels are splatted into it with the renderer's EWA set-up (an orthographic
// camera looking down the plane normal); where the brush lies below the object's surface (the depth test),
// paint is exchanged per pixel (5.9)-(5.11); the results are gathered back to the samples. Scatter and gather
// are partitions of unity over each sample's footprint, so the buffer conserves paint volume exactly.
#pragma once

#include <vector>

#include "relaxed_connectivity/paint/paint_state.h"

namespace rc {

/// One splatted sample: a surfel of the object or of the brush skin, with its paint.
struct PaintSample {
  Vec3 position = Vec3::Zero();
  Vec3 normal = Vec3::UnitZ();
  double radius = 0;
  PaintState paint;
};

/// A surfel made for one pixel when the surface is resampled (5.5).
struct PixelSurfel {
  int x = 0, y = 0;
  Vec3 position = Vec3::Zero(), normal = Vec3::UnitZ();
  double radius = 0;
  PaintState paint;
  double pressure = 0;  ///< the exchange's pressure at the pixel (0 where the brush did not penetrate)
};

struct PaintTransferStats {
  int penetrated_pixels = 0;    ///< pixels where the brush is below the surface
  double moved_to_surface = 0;  ///< wet volume the surface received
  double moved_to_brush = 0;    ///< wet volume the brush received
};

class PaintBuffer {
 public:
  enum Layer { kSurface = 0, kBrush = 1 };

  /// The least-squares plane (5.5) through `points`: their centroid and the direction of least spread,
  /// oriented to have a positive dot product with `up`. Throws std::invalid_argument for fewer than 3 points.
  static void fitPlane(const std::vector<Vec3>& points, const Vec3& up, Vec3* centre, Vec3* normal);

  /// width x height pixels of `pixel_size` (about one brush surfel, 5.5) centred at `centre` in the plane
  /// with unit `normal`. Throws std::invalid_argument for a bad size or pixel size.
  PaintBuffer(const Vec3& centre, const Vec3& normal, double pixel_size, int width, int height);

  int width() const { return width_; }
  int height() const { return height_; }
  double pixelSize() const { return pixel_size_; }
  const Vec3& normal() const { return normal_; }
  /// The world point at the centre of pixel (x, y) on the plane.
  Vec3 pixelCentre(int x, int y) const;

  /// Splats `samples` into `layer` (replacing what it held): each sample's wet volume is spread over the
  /// pixels of its EWA footprint with weights summing to one; a pixel's colour and optical density are the
  /// volume-weighted means of what it received, its height (along the normal) the weighted mean. The brush
  /// layer keeps only the penetrating parts (5.5): a brush sample enters a pixel only where it lies below
  /// the surface layer there, so splat the surface first. Samples whose footprint misses the buffer (or, on
  /// the brush, every covered pixel) are left out.
  void splat(Layer layer, const std::vector<PaintSample>& samples);

  bool covered(Layer layer, int x, int y) const { return weight_[layer][index(x, y)] > 0; }
  double height(Layer layer, int x, int y) const {
    return height_sum_[layer][index(x, y)] / weight_[layer][index(x, y)];
  }
  double volume(Layer layer, int x, int y) const { return pixel_[layer][index(x, y)].wet_volume; }
  const PaintState& pixel(Layer layer, int x, int y) const { return pixel_[layer][index(x, y)]; }

  /// The per-pixel exchange (5.9)-(5.11) where both layers cover a pixel and the brush is below the
  /// surface (the depth test): pressure = pressure_per_depth x penetration depth, for dt seconds; tau from
  /// brush to surface and back, where the layer's samples there set none (PaintState::transfer_rate < 0);
  /// else their footprint-weighted mean.
  PaintTransferStats transfer(double tau_brush_to_surface, double tau_surface_to_brush,
                              double pressure_per_depth, double dt);

  /// Gathers `layer` back into `states` (indexed like the splatted samples): each sample takes from every
  /// pixel its share of the pixel's volume (its contribution over the pixel's total, or its footprint weight
  /// where the pixel held no volume) and the pixel's colour for that volume. The sum of the samples' wet
  /// volumes equals the sum of the pixels'. Samples that were left out keep their state.
  void gather(Layer layer, std::vector<PaintState>& states) const;

  /// Surface samples with a share in a pixel where paint was exchanged by the last transfer().
  std::vector<uint8_t> penetratedSurfaceSamples() const;
  /// Resampling (5.5), instead of gather(kSurface): the samples marked in `replace` give their part of every
  /// pixel they covered to one new surfel per such pixel (on the surface layer's plane there, with its
  /// normal, a radius of one pixel, the pixel's wet colour and density, the volume of those parts, and the
  /// pixel's dry paint); the other samples take their part back as gather() does. Volume is conserved.
  void resample(const std::vector<uint8_t>& replace, std::vector<PaintState>& states,
                std::vector<PixelSurfel>& surfels) const;

 private:
  size_t index(int x, int y) const { return size_t(y) * size_t(width_) + size_t(x); }
  struct Share {
    uint32_t sample, pixel;
    double weight;      ///< the sample's footprint weight in this pixel (sums to 1 over the sample's pixels)
    double raw_weight;  ///< the kernel value before that normalisation
  };

  Vec3 centre_, normal_, axis_u_, axis_v_;
  double pixel_size_;
  int width_, height_;
  std::vector<PaintState> pixel_[2];
  std::vector<double> weight_[2], height_sum_[2], contributed_[2];
  std::vector<Share> shares_[2];
  std::vector<double> sample_volume_[2];
  std::vector<Vec3> normal_sum_;     // surface layer: footprint-weighted normals
  std::vector<PaintState> dry_;      // surface layer: footprint-weighted dry paint (colour, volume)
  std::vector<uint8_t> penetrated_;  // pixels of the last transfer
  std::vector<double> pressure_;     // and their pressure
  std::vector<double> rate_sum_[2],
      rate_weight_[2];  // footprint-weighted transfer_rate of the samples that set one
  /// The parts each splatted sample takes back from the pixels: calls take(sample, pixel, volume).
  template <class Take>
  void forEachPart(Layer layer, Take&& take) const;
};

}  // namespace rc
