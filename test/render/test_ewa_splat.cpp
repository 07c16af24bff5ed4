// EWA splat set-up (thesis 3.2): the circular-surfel path (with its scalar common case) agrees with the
// general tangent-axes path on random surfels, near-edge-on, tiny and huge ones, for both camera models.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include <cstring>

#include "relaxed_connectivity/render/splat/circular_setup_avx2.h"
#include "relaxed_connectivity/render/splat/ewa_splat.h"

namespace rc {
namespace {

void expectNear(float a, float b, double relative, const char* what) {
  EXPECT_LE(std::abs(double(a) - double(b)), relative * (1.0 + std::max(std::abs(a), std::abs(b)))) << what;
}

TEST(EwaSplat, CircularSetupAgreesWithTheAxesSetup) {
  std::mt19937 random(7);
  std::uniform_real_distribution<double> unit(-1.0, 1.0), log_radius(-5.0, 0.0);
  for (const bool perspective : {true, false}) {
    Camera camera =
        perspective ? Camera::perspective(320, 240, 60 * M_PI / 180) : Camera::orthographic(320, 240, 3.0);
    camera.lookAt(Vec3(0.3, -4, 1), Vec3::Zero());
    const CameraFrame frame(camera);
    for (const bool ewa : {true, false}) {
      EwaParams params;
      params.ewa_filter = ewa;
      size_t drawn = 0, edge_on = 0, compared = 0;
      for (int i = 0; i < 20000; ++i) {
        const Vec3 center(1.5 * unit(random), 1.5 * unit(random), 1.5 * unit(random));
        Vec3 normal(unit(random), unit(random), unit(random));
        if (i % 10 == 0) {  // nearly edge-on: normal almost perpendicular to the view ray
          const Vec3 view = (center - frame.eye).normalized();
          normal -= normal.dot(view) * view;
          normal += 1e-3 * unit(random) * view;
        }
        if (!(normal.norm() > 1e-9)) continue;
        const double radius = std::pow(10.0, log_radius(random));
        Vec3 axis1, axis2;
        tangentAxes(normal.normalized(), radius, &axis1, &axis2);
        SplatRaster circular, axes;
        float unit_normal[3];
        const SplatSetup a =
            setupCircularEwaSplat(center, normal, radius, frame, params, &circular, unit_normal);
        const SplatSetup b = setupEwaSplat(center, normal, axis1, axis2, frame, params, &axes, nullptr);
        ASSERT_EQ(a, b) << i;
        if (a != SplatSetup::kDrawn && a != SplatSetup::kDrawnEdgeOn) continue;
        drawn += a == SplatSetup::kDrawn;
        edge_on += a == SplatSetup::kDrawnEdgeOn;
        // Boxes may differ by a pixel where a bound lies on a pixel centre to rounding.
        EXPECT_LE(std::abs(int(circular.x0) - int(axes.x0)), 1);
        EXPECT_LE(std::abs(int(circular.x1) - int(axes.x1)), 1);
        EXPECT_LE(std::abs(int(circular.y0) - int(axes.y0)), 1);
        EXPECT_LE(std::abs(int(circular.y1) - int(axes.y1)), 1);
        expectNear(circular.center_u, axes.center_u, 1e-6, "center_u");
        expectNear(circular.center_v, axes.center_v, 1e-6, "center_v");
        const double conic_scale =
            std::max({std::abs(axes.conic_a), std::abs(axes.conic_b), std::abs(axes.conic_c)});
        EXPECT_LE(std::abs(circular.conic_a - axes.conic_a), 1e-4 * conic_scale) << i;
        EXPECT_LE(std::abs(circular.conic_b - axes.conic_b), 1e-4 * conic_scale) << i;
        EXPECT_LE(std::abs(circular.conic_c - axes.conic_c), 1e-4 * conic_scale) << i;
        // Depth at the centre and at the box corners.
        for (const double du : {0.0, double(axes.x0) - axes.center_u, double(axes.x1) - axes.center_u})
          for (const double dv : {0.0, double(axes.y0) - axes.center_v, double(axes.y1) - axes.center_v})
            expectNear(circular.depthAt(float(du), float(dv)), axes.depthAt(float(du), float(dv)), 1e-5,
                       "depth");
        expectNear(circular.depth_tolerance, axes.depth_tolerance, 1e-5, "tolerance");
        EXPECT_EQ(circular.flags, axes.flags);
        ++compared;
      }
      EXPECT_GT(drawn, 5000u);
      EXPECT_GT(edge_on, 100u);
      EXPECT_EQ(compared, drawn + edge_on);
    }
  }
}

// The four-wide (AVX2) set-up gives bitwise the scalar records and results: random, near-edge-on, tiny and
// huge surfels, behind the camera, outside the image, back-facing (culled or not), invalid ones. The pre-cull
// pass (unculledCircularSurfels) drops only what the set-up culls.
TEST(EwaSplat, FourWideCircularSetupIsBitwiseTheScalarOne) {
  if (!circularSetupAvx2Available()) GTEST_SKIP() << "this CPU or build has no AVX2 set-up";
  std::mt19937 random(11);
  std::uniform_real_distribution<double> unit(-1.0, 1.0), log_radius(-5.0, 0.5);
  Camera camera = Camera::perspective(320, 240, 60 * M_PI / 180);
  camera.lookAt(Vec3(0.3, -4, 1), Vec3::Zero());
  const CameraFrame frame(camera);
  size_t counts[4] = {0, 0, 0, 0};  // per SplatSetup value
  for (const bool cull : {false, true})
    for (const bool ewa : {true, false}) {
      EwaParams params;
      params.ewa_filter = ewa;
      params.backface_culling = cull;
      std::vector<Vec3> centers, normals;
      std::vector<double> radii;
      for (int i = 0; i < 8000; ++i) {
        Vec3 center(2.5 * unit(random), 2.5 * unit(random), 2.5 * unit(random));
        if (i % 97 == 0) center = frame.eye + Vec3(0, -1, 0) * unit(random);  // behind / at the camera
        Vec3 normal(unit(random), unit(random), unit(random));
        if (i % 10 == 0) {  // nearly edge-on
          const Vec3 view = (center - frame.eye).normalized();
          normal -= normal.dot(view) * view;
          normal += 1e-3 * unit(random) * view;
        }
        double radius = std::pow(10.0, log_radius(random));
        if (i % 211 == 0) radius = 0;                                             // invalid
        if (i % 223 == 0) normal = Vec3::Zero();                                  // invalid
        if (i % 227 == 0) center.x() = std::numeric_limits<double>::quiet_NaN();  // invalid
        centers.push_back(center);
        normals.push_back(normal);
        radii.push_back(radius);
      }
      // The pre-cull pass drops only surfels the set-up culls, and keeps every invalid one.
      std::vector<uint32_t> kept(centers.size());
      kept.resize(unculledCircularSurfels(centers.data(), normals.data(), radii.data(), centers.size(), frame,
                                          params, kept.data()));
      std::vector<bool> is_kept(centers.size(), false);
      for (const uint32_t i : kept) is_kept[i] = true;
      size_t dropped = 0;
      for (size_t i = 0; i < centers.size(); ++i) {
        SplatRaster raster;
        float unit_normal[3];
        const SplatSetup result =
            setupCircularEwaSplat(centers[i], normals[i], radii[i], frame, params, &raster, unit_normal);
        if (!is_kept[i]) EXPECT_EQ(int(result), int(SplatSetup::kCulled)) << "surfel " << i << " dropped";
        dropped += !is_kept[i];
      }
      EXPECT_GT(dropped, cull ? 2000u : 30u);  // back-facing, behind the camera
      for (size_t first = 0; first + 4 <= centers.size(); first += 4) {
        SplatRaster wide[4], scalar[4];
        float wide_normals[4][3], scalar_normals[4][3];
        SplatSetup wide_results[4];
        setupCircularEwaSplats4(&centers[first], &normals[first], &radii[first], frame, params, wide,
                                wide_normals, wide_results);
        for (int k = 0; k < 4; ++k) {
          const SplatSetup result =
              setupCircularEwaSplat(centers[first + k], normals[first + k], radii[first + k], frame, params,
                                    &scalar[k], scalar_normals[k]);
          ASSERT_EQ(int(result), int(wide_results[k])) << "surfel " << first + k;
          ++counts[int(result)];
          if (result != SplatSetup::kDrawn && result != SplatSetup::kDrawnEdgeOn) continue;
          EXPECT_EQ(0, std::memcmp(&wide[k], &scalar[k], sizeof(SplatRaster))) << "surfel " << first + k;
          EXPECT_EQ(0, std::memcmp(wide_normals[k], scalar_normals[k], sizeof(float[3])));
        }
      }
    }
  EXPECT_GT(counts[int(SplatSetup::kDrawn)], 10000u);
  EXPECT_GT(counts[int(SplatSetup::kDrawnEdgeOn)], 100u);
  EXPECT_GT(counts[int(SplatSetup::kCulled)], 1000u);
  EXPECT_GT(counts[int(SplatSetup::kInvalid)], 100u);
}

}  // namespace
}  // namespace rc
