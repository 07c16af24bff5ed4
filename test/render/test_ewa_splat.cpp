// EWA splat set-up (thesis 3.2): the circular-surfel path (with its scalar common case) agrees with the
// general tangent-axes path on random surfels, near-edge-on, tiny and huge ones, for both camera models.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "render/ewa_splat.h"

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

}  // namespace
}  // namespace rc
