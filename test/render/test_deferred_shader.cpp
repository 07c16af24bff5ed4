#include "relaxed_connectivity/render/splat/deferred_shader.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <random>

#include "relaxed_connectivity/render/splat/surfel_renderer.h"

namespace rc {
namespace {

// The four-wide shading of whole spans agrees with the per-pixel path (silhouette pixels, span tails): the
// same Phong model with the interpolated specular table, within one colour level (float rounding order).
TEST(DeferredShader, FourWideSpansMatchThePerPixelPath) {
  constexpr int kWidth = 64, kRows = 48;
  Camera camera = Camera::perspective(kWidth, kRows, 1.0);
  camera.lookAt(Vec3(0.5, -2, 1), Vec3::Zero());
  SplatConfig config, matte;
  config.shininess = 12;
  matte.specular = 0;
  const CameraFrame frame(camera);
  const DeferredShader shader(config, frame), matte_shader(matte, frame);
  std::mt19937 random(7);
  std::uniform_real_distribution<float> uniform(-1.0f, 1.0f);
  std::vector<float> weight(kWidth), color_weight(kWidth), depth(kWidth), color[3], normal[3];
  std::vector<int32_t> patch(kWidth);
  for (int c = 0; c < 3; ++c) color[c].resize(kWidth), normal[c].resize(kWidth);
  RenderImages wide, single, unlit;
  for (RenderImages* images : {&wide, &single, &unlit}) {
    images->width = kWidth;
    images->height = kRows;
    images->color.resize(kWidth * kRows);
    images->depth.resize(kWidth * kRows);
    images->normal.resize(kWidth * kRows);
    images->weight.resize(kWidth * kRows);
    images->patch_id.resize(kWidth * kRows);
  }
  for (int y = 0; y < kRows; ++y) {
    for (int k = 0; k < kWidth; ++k) {
      weight[k] = 0.5f + 0.5f * std::abs(uniform(random));
      color_weight[k] = weight[k];
      depth[k] = weight[k] * (3 + uniform(random));
      for (int c = 0; c < 3; ++c) {
        color[c][k] = weight[k] * 127.5f * (1 + uniform(random));
        normal[c][k] = weight[k] * uniform(random);
      }
      patch[k] = k % 3;
    }
    const AccumulatedSpan span = {weight.data(),
                                  color_weight.data(),
                                  depth.data(),
                                  {color[0].data(), color[1].data(), color[2].data()},
                                  {normal[0].data(), normal[1].data(), normal[2].data()},
                                  patch.data()};
    shader.shadeSpan(span, kWidth, 0, y, &wide);
    for (int k = 0; k < kWidth; ++k) {  // a one-pixel span takes the per-pixel path
      const AccumulatedSpan one = {span.weight + k,
                                   span.color_weight + k,
                                   span.depth + k,
                                   {span.color[0] + k, span.color[1] + k, span.color[2] + k},
                                   {span.normal[0] + k, span.normal[1] + k, span.normal[2] + k},
                                   span.patch_id + k};
      shader.shadeSpan(one, 1, k, y, &single);
      matte_shader.shadeSpan(one, 1, k, y, &unlit);
    }
  }
  shader.finish();
  matte_shader.finish();
  int largest = 0, highlighted = 0;
  for (size_t p = 0; p < wide.color.size(); ++p) {
    for (int c = 0; c < 3; ++c)
      largest = std::max(largest, std::abs(int(wide.color[p][c]) - single.color[p][c]));
    highlighted += int(single.color[p][1]) > int(unlit.color[p][1]) + 5;
    EXPECT_NEAR(wide.depth[p], single.depth[p], 1e-6f * single.depth[p]);
    EXPECT_LT((wide.normal[p] - single.normal[p]).norm(), 1e-6f);
    EXPECT_EQ(wide.patch_id[p], single.patch_id[p]);
  }
  EXPECT_LE(largest, 1);
  EXPECT_GT(highlighted, 100);  // the specular table is exercised
}

}  // namespace
}  // namespace rc
