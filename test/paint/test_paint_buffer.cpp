// The paint buffer (thesis 5.5, Fig. 5.6): the least-squares plane, splatting with the depth test, the
// per-pixel exchange, and exact conservation through scatter, transfer and gather.
#include "relaxed_connectivity/paint/paint_buffer.h"

#include <gtest/gtest.h>

#include <cmath>

namespace rc {
namespace {

constexpr double kPixel = 5e-4;

/// Samples on a square grid in the plane z = height, `half` samples each side of the centre.
std::vector<PaintSample> patch(double spacing, int half, double height, const Vec3& rgb, double volume) {
  std::vector<PaintSample> out;
  for (int y = -half; y <= half; ++y)
    for (int x = -half; x <= half; ++x) {
      PaintSample s;
      s.position = Vec3(x * spacing, y * spacing, height);
      s.radius = 1.2 * spacing;
      s.paint.wet.rgb = rgb;
      s.paint.wet_volume = volume * (1.0 + 0.1 * std::sin(0.7 * x + 0.3 * y));
      out.push_back(s);
    }
  return out;
}

double total(const std::vector<PaintState>& states) {
  double sum = 0;
  for (const PaintState& s : states) sum += s.wet_volume;
  return sum;
}

std::vector<PaintState> states(const std::vector<PaintSample>& samples) {
  std::vector<PaintState> out;
  for (const PaintSample& s : samples) out.push_back(s.paint);
  return out;
}

/// A 40 x 40 buffer at the origin in the plane z = 0 with `surface` and `brush` splatted, their paint states
/// and their total wet volume.
struct Pressed {
  PaintBuffer buffer{Vec3::Zero(), Vec3::UnitZ(), kPixel, 40, 40};
  std::vector<PaintState> s, b;
  double before;
  Pressed(const std::vector<PaintSample>& surface, const std::vector<PaintSample>& brush)
      : s(states(surface)), b(states(brush)), before(total(s) + total(b)) {
    buffer.splat(PaintBuffer::kSurface, surface);
    buffer.splat(PaintBuffer::kBrush, brush);
  }
};

/// A red brush stripe 1 mm wide along y, 0.2 mm below z = 0.
std::vector<PaintSample> stripeBrush() {
  std::vector<PaintSample> stripe;
  for (const PaintSample& s : patch(2.5e-4, 40, -2e-4, Vec3(0.9, 0.1, 0.1), 1.0))
    if (std::abs(s.position.x()) < 5e-4) stripe.push_back(s);
  return stripe;
}

TEST(PaintBuffer, FitsTheLeastSquaresPlane) {
  std::vector<Vec3> points;
  const Vec3 n = Vec3(0.2, -0.3, 1).normalized(), u = n.unitOrthogonal(), v = n.cross(u);
  for (int i = 0; i < 200; ++i)
    points.push_back(Vec3(0.1, 0.2, 0.3) + 0.01 * std::sin(i) * u + 0.01 * std::cos(1.7 * i) * v +
                     1e-5 * std::sin(13.0 * i) * n);
  Vec3 centre, normal;
  PaintBuffer::fitPlane(points, -n, &centre, &normal);
  EXPECT_NEAR(normal.dot(-n), 1.0, 1e-6);  // oriented like `up`
  EXPECT_LT(std::abs((centre - Vec3(0.1, 0.2, 0.3)).dot(n)), 1e-5);
  EXPECT_THROW(PaintBuffer::fitPlane({Vec3::Zero(), Vec3::UnitX()}, n, &centre, &normal),
               std::invalid_argument);
  PaintBuffer buffer(Vec3::Zero(), Vec3::UnitZ(), kPixel, 4, 4);
  EXPECT_THROW(buffer.splat(PaintBuffer::kBrush, {}), std::logic_error);  // the surface comes first
  EXPECT_THROW(PaintBuffer(Vec3::Zero(), Vec3::UnitZ(), 0.0, 4, 4), std::invalid_argument);
}

TEST(PaintBuffer, ConservesWetVolumeThroughSplatTransferAndGather) {
  const std::vector<PaintSample> surface = patch(1e-3, 12, 0.0, Vec3(0.1, 0.2, 0.9), 0.3);
  const std::vector<PaintSample> brush = patch(4e-4, 15, -2e-4, Vec3(0.9, 0.1, 0.1), 1.0);  // 0.2 mm deep
  Pressed pressed(surface, brush);
  PaintBuffer& buffer = pressed.buffer;
  std::vector<PaintState>&s = pressed.s, &b = pressed.b;
  const double before = pressed.before;
  const PaintTransferStats stats = buffer.transfer(4.0, 4.0, 2000.0, 1.0 / 30);
  EXPECT_GT(stats.penetrated_pixels, 400);
  EXPECT_GT(stats.moved_to_surface, 0.01 * before);
  buffer.gather(PaintBuffer::kSurface, s);
  buffer.gather(PaintBuffer::kBrush, b);
  EXPECT_NEAR(total(s) + total(b), before, 1e-12 * before);
  // Paint went both ways: the surface turned towards red, the brush towards blue.
  EXPECT_GT(s[s.size() / 2].wet.rgb.x(), 0.2);
  EXPECT_GT(b[b.size() / 2].wet.rgb.z(), 0.1 + 1e-3);
}

TEST(PaintBuffer, NoTransferToTheBrushLeavesItsPaintUnmixed) {
  // Fig. 5.8 bottom, through the whole buffer.
  const std::vector<PaintSample> surface = patch(1e-3, 12, 0.0, Vec3(0.1, 0.2, 0.9), 0.3);
  const std::vector<PaintSample> brush = patch(4e-4, 15, -2e-4, Vec3(0.9, 0.1, 0.1), 1.0);
  Pressed pressed(surface, brush);
  PaintBuffer& buffer = pressed.buffer;
  std::vector<PaintState>&s = pressed.s, &b = pressed.b;
  const double before = pressed.before;
  buffer.transfer(4.0, 0.0, 2000.0, 1.0 / 30);
  buffer.gather(PaintBuffer::kSurface, s);
  buffer.gather(PaintBuffer::kBrush, b);
  EXPECT_NEAR(total(s) + total(b), before, 1e-12 * before);
  for (size_t i = 0; i < b.size(); ++i) {
    EXPECT_LE(b[i].wet_volume, brush[i].paint.wet_volume * (1 + 1e-12)) << "brush sample " << i;
    EXPECT_LT((b[i].wet.rgb - Vec3(0.9, 0.1, 0.1)).norm(), 1e-12) << "brush sample " << i;
  }
}

TEST(PaintBuffer, OnlyPenetratingBrushPartsTakePart) {
  const std::vector<PaintSample> surface = patch(1e-3, 12, 0.0, Vec3(0.1, 0.2, 0.9), 0.3);
  const std::vector<PaintSample> above = patch(4e-4, 15, 1e-3, Vec3(0.9, 0.1, 0.1), 1.0);  // 1 mm above
  Pressed pressed(surface, above);
  EXPECT_EQ(pressed.buffer.transfer(4.0, 4.0, 2000.0, 1.0 / 30).penetrated_pixels, 0);
  std::vector<PaintState>& b = pressed.b;
  pressed.buffer.gather(PaintBuffer::kBrush, b);
  for (size_t i = 0; i < b.size(); ++i) EXPECT_EQ(b[i], above[i].paint);
}

TEST(PaintBuffer, HoldsAStripeNarrowerThanTheSurfaceSampling) {
  // A bare surface sampled every 2 mm; a brush stripe 1 mm wide (two pixels) pressed into it. The surface
  // layer receives the stripe at pixel resolution: edges within 2 pixels of the stripe's.
  const std::vector<PaintSample> surface = patch(2e-3, 6, 0.0, Vec3(1, 1, 1), 0.0);
  Pressed pressed(surface, stripeBrush());
  PaintBuffer& buffer = pressed.buffer;
  buffer.transfer(4.0, 4.0, 2000.0, 1.0 / 30);
  // Classified by the world x of each pixel centre (the buffer's own axes need not be the world's).
  double peak = 0;
  for (int y = 0; y < 40; ++y)
    for (int x = 0; x < 40; ++x) peak = std::max(peak, buffer.volume(PaintBuffer::kSurface, x, y));
  ASSERT_GT(peak, 0);
  int inside = 0, outside = 0;
  for (int y = 0; y < 40; ++y)
    for (int x = 0; x < 40; ++x) {
      const Vec3 centre = buffer.pixelCentre(x, y);
      if (std::abs(centre.y()) > 8e-3) continue;  // away from the stripe's ends
      const double offset = std::abs(centre.x()), v = buffer.volume(PaintBuffer::kSurface, x, y) / peak;
      if (offset < 2.6e-4) {  // inside the stripe (the pixels at +-0.25 mm)
        ++inside;
        EXPECT_GT(v, 0.5) << x << ", " << y;
      }
      if (offset > 5e-4 + 2 * kPixel) {  // 2 pixels beyond its edge
        ++outside;
        EXPECT_LT(v, 1e-3) << x << ", " << y;
      }
    }
  EXPECT_GT(inside, 40);
  EXPECT_GT(outside, 400);
}

TEST(PaintBuffer, ResamplingReplacesThePenetratedSurfelsByPixelSurfelsAndConservesPaint) {
  const std::vector<PaintSample> surface = patch(2e-3, 6, 0.0, Vec3(0.1, 0.2, 0.9), 0.3);
  const std::vector<PaintSample> stripe = stripeBrush();  // 1 mm wide, narrower than the 2 mm sampling
  Pressed pressed(surface, stripe);
  PaintBuffer& buffer = pressed.buffer;
  std::vector<PaintState>&s = pressed.s, &b = pressed.b;
  const double before = pressed.before;
  buffer.transfer(4.0, 4.0, 2000.0, 1.0 / 30);
  const std::vector<uint8_t> replace = buffer.penetratedSurfaceSamples();
  size_t replaced = 0;
  for (uint8_t r : replace) replaced += r;
  EXPECT_GT(replaced, 0u);
  EXPECT_LT(replaced, surface.size());
  std::vector<PixelSurfel> children;
  buffer.resample(replace, s, children);
  buffer.gather(PaintBuffer::kBrush, b);
  // Conservation: the kept surfels, the new pixel surfels and the brush.
  double after = total(b);
  for (size_t i = 0; i < s.size(); ++i)
    if (!replace[i]) after += s[i].wet_volume;
  for (const PixelSurfel& c : children) after += c.paint.wet_volume;
  EXPECT_NEAR(after, before, 1e-12 * before);
  // One surfel per pixel, on the surface (z = 0), facing up, a pixel wide.
  EXPECT_GT(children.size(), 100u);
  for (const PixelSurfel& c : children) {
    EXPECT_NEAR(c.position.z(), 0.0, 1e-6);
    EXPECT_NEAR(c.normal.z(), 1.0, 1e-12);
    EXPECT_EQ(c.radius, kPixel);
  }
  // The stripe at pixel resolution: red inside, the surface's blue two pixels beyond its edge.
  int inside = 0, outside = 0;
  for (const PixelSurfel& c : children) {
    const double offset = std::abs(c.position.x());
    if (offset < 2.6e-4) {
      ++inside;
      EXPECT_GT(c.paint.wet.rgb.x(), 0.5) << c.x << ", " << c.y;
    }
    if (offset > 5e-4 + 2 * kPixel) {
      ++outside;
      EXPECT_LT(c.paint.wet.rgb.x(), 0.1 + 1e-3) << c.x << ", " << c.y;
    }
  }
  EXPECT_GT(inside, 20);
  EXPECT_GT(outside, 20);
}

}  // namespace
}  // namespace rc
