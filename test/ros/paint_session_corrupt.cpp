// Corrupt messages into a running paint session (paint_session_corrupt.test) while the recorded bag plays:
// device poses with NaN, scanner clouds and paint deltas whose data is cut short. Every one is refused and
// counted; the session keeps painting (the model makes children after them) and rendering (frames after
// them).
#include <sensor_msgs/PointCloud2.h>

#include <limits>

#include "paint_session_support.h"

namespace rc {
namespace {

sensor_msgs::PointCloud2 truncatedCloud(const std::string& frame) {
  sensor_msgs::PointCloud2 cloud;
  cloud.header.frame_id = frame;
  cloud.header.stamp = ros::Time::now();
  cloud.height = 1;
  cloud.width = 1000;
  sensor_msgs::PointField f;
  f.datatype = sensor_msgs::PointField::FLOAT32;
  f.count = 1;
  for (const char* name : {"x", "y", "z"}) {
    f.name = name;
    f.offset = uint32_t(cloud.fields.size() * 4);
    cloud.fields.push_back(f);
  }
  cloud.point_step = 12;
  cloud.row_step = 12 * cloud.width;
  cloud.data.resize(100 * 12);  // 100 of the 1000 points announced
  return cloud;
}

TEST(PaintSessionCorrupt, BadMessagesAreRefusedAndTheSessionGoesOn) {
  ros::NodeHandle nh;
  SessionObserver session(nh);
  ros::Publisher pose_pub = nh.advertise<geometry_msgs::PoseStamped>("haptic/pose", 10);
  ros::Publisher points_pub = nh.advertise<sensor_msgs::PointCloud2>("points", 2);
  ros::Publisher delta_pub = nh.advertise<relaxed_connectivity::PaintDelta>("surfels/painted_delta", 10);
  // Wait until the brush paints, then inject.
  ASSERT_TRUE(waitFor([&] { return session.paint_stats.children > 0; }, 60.0)) << "no painting";
  const uint32_t children_before = session.paint_stats.children;
  const size_t images_before = session.image_count;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (int k = 0; k < 10; ++k) {
    geometry_msgs::PoseStamped pose;
    pose.header.frame_id = "haptic_base";
    pose.header.stamp = ros::Time::now();
    pose.pose.position.x = nan;
    pose.pose.orientation.w = 1;
    pose_pub.publish(pose);
    points_pub.publish(truncatedCloud("scanner_optical"));
    relaxed_connectivity::PaintDelta delta;
    delta.header.stamp = ros::Time::now();
    delta.sequence = 1u << 30;
    delta.originals = {0, 1, 2};
    delta.surfels = truncatedCloud("world");
    delta_pub.publish(delta);
    waitFor([] { return false; }, 0.05);
  }
  ASSERT_TRUE(session.waitForTheEnd(90.0));
  ASSERT_TRUE(
      waitFor([&] { return session.render_stats.header.stamp > ros::Time::now() - ros::Duration(0.5); }, 5));
  EXPECT_GT(session.paint_stats.children, children_before) << "painting stopped";
  EXPECT_GT(session.image_count, images_before + 10) << "rendering stopped";
  EXPECT_GE(session.paint_stats.rejected_messages, 10u);  // the NaN poses
  EXPECT_GE(session.render_stats.rejected_messages, 10u) << session.render_stats.last_error;
  EXPECT_EQ(session.render_stats.sequence_gaps, 0u);  // a refused delta does not count as one
  EXPECT_EQ(session.render_stats.surfels, session.paint_stats.active_surfels);
}

}  // namespace
}  // namespace rc

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "paint_session_corrupt");
  return RUN_ALL_TESTS();
}
