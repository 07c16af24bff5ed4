// The recorded paint session bag through the session's nodes (paint_session_bag.test): the object is scanned
// and painted, the renderer follows every delta differentially, and its last image equals a full render of
// the state paint_model saves (same parameters, same camera) within the differential rendering bound of
// test_painted_cloud_mirror (acrylic's imprints: mean below 6 levels over the painted pixels; here over the
// image, where most pixels are unpainted and exact).
#include <relaxed_connectivity/PaintFile.h>
#include <tf2_eigen/tf2_eigen.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>

#include <cstdio>

#include "paint_session_support.h"
#include "relaxed_connectivity/paint/painted_surface_io.h"
#include "relaxed_connectivity/render/splat/differential_renderer.h"
#include "relaxed_connectivity/ros/paint_renderer.h"

namespace rc {
namespace {

TEST(PaintSessionBag, PaintsAndTheImageEqualsAFullRenderOfTheSavedState) {
  ros::NodeHandle nh;
  SessionObserver session(nh);
  tf2_ros::Buffer tf_buffer;
  tf2_ros::TransformListener tf_listener(tf_buffer);
  ASSERT_TRUE(session.waitForTheEnd(90.0))
      << session.pose_count << " poses, " << session.delta_count << " deltas";
  ASSERT_TRUE(
      waitFor([&] { return session.render_stats.header.stamp > ros::Time::now() - ros::Duration(0.5); }, 5));

  // Painted: children made by resampling, wet paint; nothing refused.
  const relaxed_connectivity::PaintStats& p = session.paint_stats;
  EXPECT_GT(p.originals, 10000u);
  EXPECT_GT(p.children, 500u);
  EXPECT_GT(p.wet_surfels, 500u);
  EXPECT_EQ(p.rejected_messages, 0u);
  EXPECT_EQ(p.instabilities, 0u);
  // Rendered: mostly differential updates, no gap, nothing refused, the copy as large as the object.
  const relaxed_connectivity::PaintRenderStats& r = session.render_stats;
  EXPECT_GT(session.differential_updates, 20u);
  EXPECT_GT(session.differential_updates, 4 * session.full_updates);
  EXPECT_EQ(r.sequence_gaps, 0u);
  EXPECT_EQ(r.rejected_messages, 0u) << r.last_error;
  EXPECT_EQ(r.surfels, p.active_surfels);

  // The saved state, rendered whole with the node's parameters and camera.
  relaxed_connectivity::PaintFile save;
  save.request.path = "/tmp/paint_session_bag_" + std::to_string(::getpid()) + ".ply";
  ASSERT_TRUE(ros::service::call("paint_model/save", save));
  ASSERT_TRUE(save.response.success) << save.response.message;
  const std::unique_ptr<PaintSurface> saved = loadPaintedSurface(save.request.path);
  std::remove(save.request.path.c_str());
  EXPECT_EQ(saved->activeCount(), r.surfels);
  const PaintRendererParams params = readPaintRendererParams(ros::NodeHandle("paint_renderer"));
  Camera camera = params.camera();
  ASSERT_TRUE(waitFor(
      [&] { return tf_buffer.canTransform(params.fixed_frame, params.camera_frame, ros::Time(0)); }, 5));
  camera.world_T_camera =
      tf2::transformToEigen(tf_buffer.lookupTransform(params.fixed_frame, params.camera_frame, ros::Time(0)));
  DifferentialRenderConfig config = params.render;
  const EnvironmentMap studio = EnvironmentMap::studio();  // the node's default environment
  ASSERT_EQ(params.environment, "studio");
  config.splat.environment = &studio;
  DifferentialSurfelRenderer reference(config);
  reference.renderFull(saved->activeCloud(), camera);

  ASSERT_TRUE(session.image);
  const sensor_msgs::Image& image = *session.image;
  ASSERT_EQ(image.width, camera.width);
  ASSERT_EQ(image.height, camera.height);
  double mean = 0;
  size_t over_eight = 0, painted = 0;
  const std::vector<Rgba>& expected = reference.images().color;
  for (size_t i = 0; i < expected.size(); ++i) {
    int d = 0;
    for (int c = 0; c < 3; ++c) d = std::max(d, std::abs(int(image.data[3 * i + c]) - int(expected[i][c])));
    mean += d;
    over_eight += d > 8;
  }
  mean /= double(expected.size());
  for (const auto& c : saved->activeCloud().colors)
    painted += c[0] > 2 * c[2];  // red acrylic on the purple box
  std::printf(
      "session: %u originals, %u children, %zu deltas; image against a full render: mean %.3f levels, "
      "%zu of %zu pixels over 8 levels; %zu red surfels\n",
      p.originals, p.children, session.delta_count, mean, over_eight, expected.size(), painted);
  EXPECT_LT(mean, 0.5);
  EXPECT_LT(double(over_eight), 0.01 * double(expected.size()));
  EXPECT_GT(painted, 200u);
}

}  // namespace
}  // namespace rc

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "paint_session_bag");
  return RUN_ALL_TESTS();
}
