// The recorded session bag with bad messages among its own (paint_session_corrupt.test): 30 device poses
// (NaN, infinite, non-unit quaternions), 10 scanner clouds (cut short, a point step smaller than the fields,
// rows longer than the data) and 10 paint deltas cut short, all while the brush paints. Every one is refused
// and counted by the node it reaches; the session keeps painting (as much as the clean bag paints) and
// rendering, and the renderer's copy stays equal to the model.
#include <relaxed_connectivity/SurfelStats.h>

#include "paint_session_support.h"

namespace rc {
namespace {

TEST(PaintSessionCorrupt, BadMessagesAreRefusedAndTheSessionGoesOn) {
  ros::NodeHandle nh;
  SessionObserver session(nh);
  relaxed_connectivity::SurfelStats scanner_stats;
  size_t scanner_messages = 0;
  ros::Subscriber scanner =
      nh.subscribe<relaxed_connectivity::SurfelStats>("surfel_estimator/stats", 100, [&](const auto& m) {
        scanner_stats = *m;
        ++scanner_messages;
      });
  ASSERT_TRUE(session.waitForTheEnd(90.0))
      << session.pose_count << " poses, " << session.delta_count << " deltas";
  ASSERT_TRUE(
      waitFor([&] { return session.render_stats.header.stamp > ros::Time::now() - ros::Duration(0.5); }, 5));
  const relaxed_connectivity::PaintStats& p = session.paint_stats;
  const relaxed_connectivity::PaintRenderStats& r = session.render_stats;
  std::printf(
      "refused: %u by paint_model, %u by surfel_estimator (%s), %u by paint_renderer (%s); painted: %u "
      "children, "
      "%u wet surfels; %zu images\n",
      p.rejected_messages, scanner_stats.rejected_messages, scanner_stats.last_error.c_str(),
      r.rejected_messages, r.last_error.c_str(), p.children, p.wet_surfels, session.image_count);
  EXPECT_EQ(p.rejected_messages, 30u);                  // the poses (as the clean bag: no object refused)
  EXPECT_EQ(scanner_stats.rejected_messages, 10u);      // the clouds
  EXPECT_EQ(scanner_messages, 16u);                     // one stats message per cloud, good or bad
  EXPECT_EQ(r.rejected_messages, 10u) << r.last_error;  // the deltas
  // Painting went on through them (the clean bag: about 4100 children, 850 red surfels) ...
  EXPECT_GT(p.children, 3000u);
  EXPECT_GT(p.wet_surfels, 500u);
  EXPECT_EQ(p.instabilities, 0u);
  // ... and rendering: differential updates, no gap (a refused delta is not one), the copy equal to the
  // model.
  EXPECT_GT(session.differential_updates, 20u);
  EXPECT_EQ(r.sequence_gaps, 0u);
  EXPECT_EQ(r.surfels, p.active_surfels);
}

}  // namespace
}  // namespace rc

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "paint_session_corrupt");
  return RUN_ALL_TESTS();
}
