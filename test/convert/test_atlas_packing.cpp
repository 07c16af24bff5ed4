// Atlas packing (thesis 6.3, Algorithm 6.1): every patch lands on a page, whole and unscaled (mirrored at
// most), no texel is claimed by two patches, the usage is stated and high for many small patches, the result
// is deterministic, and bad patches are refused by index.
#include "relaxed_connectivity/convert/atlas_packing.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <random>

namespace rc {
namespace {

std::vector<PatchShape> randomPatches(size_t n, double scale, unsigned seed) {
  std::mt19937 random(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<PatchShape> patches;
  for (size_t i = 0; i < n; ++i) {
    PatchShape p;
    p.base = scale * (4 + 30 * unit(random));
    p.height = p.base * (0.15 + 0.8 * unit(random));  // (a longest base: height <= base sqrt(3)/2)
    p.apex_x = p.base * (0.05 + 0.9 * unit(random));
    patches.push_back(p);
  }
  return patches;
}

/// Draws every patch's mask at its placement; returns the texels claimed twice (and fails on texels outside).
size_t overlaps(const std::vector<PatchShape>& patches, const AtlasLayout& layout, int border) {
  const int P = layout.page_size;
  std::vector<std::vector<unsigned char>> pages(size_t(layout.pages),
                                                std::vector<unsigned char>(size_t(P) * P, 0));
  size_t twice = 0;
  for (size_t i = 0; i < patches.size(); ++i) {
    const PatchPlacement& at = layout.placements[i];
    const PatchMask m = patchMask(patches[i], border);
    const double x0 = at.corners[0].x() - (at.flipped_horizontally ? m.width - m.origin : m.origin);
    const double y0 = at.corners[0].y() - (at.flipped_vertically ? m.height - m.origin : m.origin);
    EXPECT_EQ(x0, std::round(x0));
    EXPECT_EQ(y0, std::round(y0));
    for (int y = 0; y < m.height; ++y)
      for (int x = 0; x < m.width; ++x) {
        if (!m.texels[size_t(y) * m.width + x]) continue;
        const int px = int(x0) + (at.flipped_horizontally ? m.width - 1 - x : x);
        const int py = int(y0) + (at.flipped_vertically ? m.height - 1 - y : y);
        if (px < 0 || py < 0 || px >= P || py >= P) {
          ADD_FAILURE() << "patch " << i << " leaves its page at (" << px << ", " << py << ")";
          return twice;
        }
        unsigned char& texel = pages[size_t(at.page)][size_t(py) * P + px];
        twice += texel != 0;
        texel = 1;
      }
  }
  return twice;
}

TEST(AtlasPacking, PatchesAreWholeUnscaledAndNeverShareATexel) {
  const std::vector<PatchShape> patches = randomPatches(2000, 1.0, 7);
  AtlasOptions options;
  const AtlasLayout layout = packPatches(patches, options);
  std::printf(
      "2000 patches of 4-34 texels: %d page(s) of %d (last %d high), usage %.1f %% (%.1f %% with borders)\n",
      layout.pages, layout.page_size, layout.last_page_height, 100 * layout.usage,
      100 * layout.usage_with_borders);
  EXPECT_EQ(overlaps(patches, layout, options.border), 0u);
  for (size_t i = 0; i < patches.size(); ++i) {  // the same triangle: edge lengths kept (mirrors allowed)
    const PatchPlacement& at = layout.placements[i];
    ASSERT_GE(at.page, 0) << "patch " << i << " was not placed";
    const double base = (at.corners[1] - at.corners[0]).norm();
    const double apex_to_start = (at.corners[2] - at.corners[0]).norm();
    EXPECT_NEAR(base, patches[i].base, 1e-9);
    EXPECT_NEAR(apex_to_start, std::hypot(patches[i].apex_x, patches[i].height), 1e-9);
  }
  // Measured: 92.5 % of the atlas claimed by patches with their borders, 60.7 % inside triangles (81 % and
  // 44 % before the rows were filled to their ends and gaps): a 1-texel border around triangles of 4-34
  // texels claims nearly as much as the triangles themselves.
  EXPECT_GT(layout.usage_with_borders, 0.88);
  EXPECT_GT(layout.usage, 0.55);
}

TEST(AtlasPacking, TheGapFillTradesPackingTimeForUsage) {
  // A few tall patches among many short ones, as a simplified mesh's detailed and flat triangles give.
  std::vector<PatchShape> patches = randomPatches(2000, 1.0, 7);
  for (const PatchShape& tall : randomPatches(30, 4.0, 9)) patches.push_back(tall);
  AtlasOptions rows_only;
  rows_only.fill_gaps = false;
  const AtlasLayout a = packPatches(patches, rows_only), b = packPatches(patches, AtlasOptions());
  EXPECT_EQ(overlaps(patches, a, rows_only.border), 0u);
  std::printf(
      "rows and row ends only: usage %.1f %% (%.1f %% with borders); with the gap fill %.1f %% (%.1f %%)\n",
      100 * a.usage, 100 * a.usage_with_borders, 100 * b.usage, 100 * b.usage_with_borders);
  // Measured 86.5 % and 93.0 % with borders: the wedges between the tall patches hold many short ones.
  EXPECT_GT(b.usage_with_borders, a.usage_with_borders + 0.05);
  EXPECT_GT(a.usage_with_borders, 0.75);
}

TEST(AtlasPacking, ManyPatchesSpillOntoMorePagesAndStayDeterministic) {
  const std::vector<PatchShape> patches = randomPatches(3000, 1.5, 11);
  AtlasOptions options;
  options.page_size = 256;
  const AtlasLayout a = packPatches(patches, options), b = packPatches(patches, options);
  EXPECT_GT(a.pages, 2);
  EXPECT_EQ(overlaps(patches, a, options.border), 0u);
  for (size_t i = 0; i < patches.size(); ++i) {
    EXPECT_EQ(a.placements[i].page, b.placements[i].page);
    EXPECT_EQ(a.placements[i].corners[2], b.placements[i].corners[2]);
  }
  std::printf("3000 patches on %d pages of 256: usage %.1f %%\n", a.pages, 100 * a.usage);
}

TEST(AtlasPacking, ATriangleBecomesItsPatch) {
  // A 3-4-5 right triangle at 10 texels per unit: the hypotenuse is the base (50 texels), the apex 24 high,
  // 32 texels along the base from the vertex the base starts at.
  const PatchShape p = PatchShape::ofTriangle(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(4, 0, 0),
                                              Eigen::Vector3d(0, 3, 0), 10.0);
  EXPECT_NEAR(p.base, 50.0, 1e-12);
  EXPECT_NEAR(p.height, 24.0, 1e-12);
  EXPECT_TRUE(std::abs(p.apex_x - 32.0) < 1e-9 || std::abs(p.apex_x - 18.0) < 1e-9) << p.apex_x;
}

TEST(AtlasPacking, BadPatchesAreRefusedByIndex) {
  std::vector<PatchShape> patches = randomPatches(10, 1.0, 3);
  patches[6].apex_x = patches[6].base + 1;
  try {
    packPatches(patches);
    ADD_FAILURE() << "an apex outside the base was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("patch 6"), std::string::npos) << e.what();
  }
  patches[6].apex_x = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(packPatches(patches), std::invalid_argument);
  AtlasOptions small;
  small.page_size = 16;
  EXPECT_THROW(packPatches(randomPatches(3, 1.0, 3), small), std::invalid_argument);  // 34-texel patches
  small.page_size = 100;
  EXPECT_THROW(packPatches(randomPatches(3, 1.0, 3), small), std::invalid_argument);  // not a power of two
  EXPECT_EQ(packPatches({}).pages, 0);
}

}  // namespace
}  // namespace rc
