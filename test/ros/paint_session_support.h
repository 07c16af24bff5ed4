// Shared by the paint session rostests (paint_session_nodes.launch): what the session publishes, collected
// while the recorded bag plays, and the wait for the bag's end.
#pragma once

#include <geometry_msgs/PoseStamped.h>
#include <gtest/gtest.h>
#include <relaxed_connectivity/PaintDelta.h>
#include <relaxed_connectivity/PaintRenderStats.h>
#include <relaxed_connectivity/PaintStats.h>
#include <ros/ros.h>
#include <sensor_msgs/Image.h>

#include <string>

#include "launch_test_support.h"

namespace rc {

struct SessionObserver {
  explicit SessionObserver(ros::NodeHandle& nh) {
    poses = nh.subscribe<geometry_msgs::PoseStamped>("haptic/pose", 100, [this](const auto&) {
      ++pose_count;
      last_pose = ros::WallTime::now();
    });
    deltas =
        nh.subscribe<relaxed_connectivity::PaintDelta>("surfels/painted_delta", 100, [this](const auto&) {
          ++delta_count;
          last_delta = ros::WallTime::now();
        });
    paint = nh.subscribe<relaxed_connectivity::PaintStats>("paint_stats", 10,
                                                           [this](const auto& m) { paint_stats = *m; });
    render = nh.subscribe<relaxed_connectivity::PaintRenderStats>(
        "paint_renderer/stats", 10, [this](const auto& m) {
          render_stats = *m;
          frames += m->frames;
          differential_updates += m->differential_updates;
          full_updates += m->full_updates;
        });
    images = nh.subscribe<sensor_msgs::Image>("paint_renderer/image", 2,
                                              [this](const sensor_msgs::ImageConstPtr& m) {
                                                image = m;
                                                ++image_count;
                                              });
  }

  /// Spins until the bag has played its poses and the paint model has sent no delta for `quiet` seconds.
  bool waitForTheEnd(double timeout, double quiet = 1.5) {
    return waitFor(
        [&] {
          const ros::WallTime now = ros::WallTime::now();
          return pose_count > 1000 && (now - last_pose).toSec() > 2.0 && delta_count > 0 &&
                 (now - last_delta).toSec() > quiet;
        },
        timeout);
  }

  ros::Subscriber poses, deltas, paint, render, images;
  size_t pose_count = 0, delta_count = 0, image_count = 0;
  ros::WallTime last_pose, last_delta;
  relaxed_connectivity::PaintStats paint_stats;
  relaxed_connectivity::PaintRenderStats render_stats;
  uint32_t frames = 0, differential_updates = 0, full_updates = 0;
  sensor_msgs::ImageConstPtr image;
};

}  // namespace rc
