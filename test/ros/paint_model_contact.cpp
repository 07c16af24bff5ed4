// paint_model: brush contact against a surfel plane, expressed in the device's pose frame; bad input is
// dropped.
#include <geometry_msgs/PoseStamped.h>
#include <gtest/gtest.h>
#include <relaxed_connectivity/BrushContact.h>
#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>
#include <visualization_msgs/MarkerArray.h>

#include <cmath>
#include <limits>
#include <mutex>

#include "relaxed_connectivity/ros/point_cloud2_converter.h"

namespace {

using relaxed_connectivity::BrushContact;

/// The plane z = 0 of `world`, 8 cm square, 0.5 mm grid, normals +z.
sensor_msgs::PointCloud2Ptr planeMessage(bool with_normals) {
  rc::SurfelCloud c;
  for (int i = -80; i <= 80; ++i)
    for (int j = -80; j <= 80; ++j) {
      c.positions.push_back(rc::Vec3(0.1 + 0.0005 * i, 0.0005 * j, 0));
      if (with_normals) c.normals.push_back(rc::Vec3::UnitZ());
    }
  c.frame_id = "world";
  return rc::PointCloud2Converter::toMessage(c);
}

class PaintModelContact : public ::testing::Test {
 protected:
  void SetUp() override {
    ros::NodeHandle nh;
    surfels_pub_ = nh.advertise<sensor_msgs::PointCloud2>("surfels", 1, /*latch=*/true);
    pose_pub_ = nh.advertise<geometry_msgs::PoseStamped>("haptic/pose", 10);
    contact_sub_ = nh.subscribe<BrushContact>("brush_contact", 100, [this](const auto& m) {
      std::lock_guard<std::mutex> lock(mutex_);
      latest_ = *m;
      ++contacts_;
    });
    skeleton_sub_ = nh.subscribe<visualization_msgs::MarkerArray>("brush/skeleton", 2, [this](const auto& m) {
      std::lock_guard<std::mutex> lock(mutex_);
      skeleton_ = *m;
    });
    const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(20.0);
    while ((pose_pub_.getNumSubscribers() == 0 || surfels_pub_.getNumSubscribers() == 0) &&
           ros::WallTime::now() < end)
      ros::WallDuration(0.05).sleep();
    ASSERT_GT(pose_pub_.getNumSubscribers(), 0u) << "paint_model is not running";
  }

  /// Publishes the stylus pose (bristles down) with the ferrule at height z of the world, i.e. z - 0.2 in
  /// haptic_base (the static tf puts haptic_base at (0.1, 0, 0.2)), for `seconds`.
  void hold(double z, double seconds, double qw = 1.0) {
    geometry_msgs::PoseStamped p;
    p.header.frame_id = "haptic_base";
    p.pose.position.z = z - 0.2;
    p.pose.orientation.w = qw;
    const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(seconds);
    while (ros::WallTime::now() < end) {
      p.header.stamp = ros::Time::now();
      pose_pub_.publish(p);
      ros::WallDuration(0.005).sleep();
    }
  }

  BrushContact latest() {
    std::lock_guard<std::mutex> lock(mutex_);
    return latest_;
  }
  size_t contacts() {
    std::lock_guard<std::mutex> lock(mutex_);
    return contacts_;
  }

  ros::Publisher surfels_pub_, pose_pub_;
  ros::Subscriber contact_sub_, skeleton_sub_;
  std::mutex mutex_;
  BrushContact latest_;
  size_t contacts_ = 0;
  visualization_msgs::MarkerArray skeleton_;
};

TEST_F(PaintModelContact, HandleContactsCarryTheAnalyticDepthAndNormalInThePoseFrame) {
  surfels_pub_.publish(planeMessage(false));  // rejected: no normals (logged); there is no object yet
  hold(0.03, 0.5);
  EXPECT_GT(contacts(), 10u);
  EXPECT_TRUE(latest().handles.empty());
  surfels_pub_.publish(planeMessage(true));
  hold(0.03, 0.5);  // brush 3 cm above the plane (its bristles are 2 cm long): no contact
  EXPECT_TRUE(latest().handles.empty());
  hold(0.005, 1.0);  // ferrule 5 mm above: bristles bend on the plane, the handle is free
  EXPECT_TRUE(latest().handles.empty());
  EXPECT_GT(latest().bristle_force.z, 0.0);  // the bent bristles push the stylus up
  hold(-0.0015, 0.5);                        // ferrule 1.5 mm below the plane
  const BrushContact c = latest();
  EXPECT_EQ(c.header.frame_id, "haptic_base");
  EXPECT_DOUBLE_EQ(c.penalty_stiffness, 400.0);
  EXPECT_DOUBLE_EQ(c.friction, 2.0);
  ASSERT_EQ(c.handles.size(), 7u);  // the ferrule's axis and ring points; the apex in the handle is above
  for (const auto& h : c.handles) {
    EXPECT_LT(h.index, 8u);
    EXPECT_NEAR(h.depth, 0.0015, 1e-9);
    EXPECT_NEAR(h.normal.z, 1.0, 1e-12);
    EXPECT_NEAR(h.position.z, -0.0015 - 0.2, 1e-9);  // in haptic_base
  }
  // A NaN pose and a non-unit quaternion are dropped: the brush stays where it was.
  hold(std::numeric_limits<double>::quiet_NaN(), 0.3);
  hold(0.03, 0.3, 0.5);
  EXPECT_EQ(latest().handles.size(), 7u);
  std::lock_guard<std::mutex> lock(mutex_);
  ASSERT_EQ(skeleton_.markers.size(), 3u);
  EXPECT_EQ(skeleton_.markers[0].points.size(), 8u);  // handle points
  EXPECT_EQ(skeleton_.markers[1].points.size(), 3u);  // active masses
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "paint_model_contact_test");
  ros::NodeHandle nh;
  ros::AsyncSpinner spinner(1);
  spinner.start();
  return RUN_ALL_TESTS();
}
