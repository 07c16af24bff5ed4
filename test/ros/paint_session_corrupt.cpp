// The recorded session bag with bad messages among its own (paint_session_corrupt.test): 30 device poses
// (NaN, infinite, non-unit quaternions), 10 scanner clouds (cut short, a point step smaller than the fields,
// rows longer than the data) and 10 paint deltas cut short, all while the brush paints. Every one is refused
// and counted by the node it reaches; the session keeps painting (as much as the clean bag paints) and
// rendering, and the renderer's copy stays equal to the model.
#include <diagnostic_msgs/DiagnosticArray.h>
#include <relaxed_connectivity/SurfelStats.h>

#include <map>
#include <string>

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
  std::map<std::string, std::map<std::string, std::string>> diagnostics;  // status name -> key -> value
  ros::Subscriber diagnostics_sub = nh.subscribe<diagnostic_msgs::DiagnosticArray>(
      "/diagnostics", 100, [&](const diagnostic_msgs::DiagnosticArrayConstPtr& m) {
        for (const auto& status : m->status)
          for (const auto& kv : status.values) diagnostics[status.name][kv.key] = kv.value;
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
  // /diagnostics counts them per input as well.
  EXPECT_TRUE(waitFor(
      [&] {
        return diagnostics["paint_model: input /haptic/pose"]["rejected"] == "30" &&
               diagnostics["surfel_estimator: input /points"]["rejected"] == "10" &&
               diagnostics["paint_renderer: input /surfels/painted_delta"]["rejected"] == "10";
      },
      5))
      << "pose input: " << diagnostics["paint_model: input /haptic/pose"]["rejected"]
      << " rejected, cloud input: " << diagnostics["surfel_estimator: input /points"]["rejected"]
      << ", delta input: " << diagnostics["paint_renderer: input /surfels/painted_delta"]["rejected"];
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
