// Shared by the demo launch rostests: waiting while spinning, simulator commands and ~save, and the check
// that an rviz config shows only topics somebody publishes.
#pragma once

#include <gtest/gtest.h>
#include <relaxed_connectivity/SaveState.h>
#include <relaxed_connectivity/SimulationCommand.h>
#include <ros/ros.h>
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cstdio>
#include <string>

#include "relaxed_connectivity/io/cloud_io.h"

namespace rc {

/// Spins until done() or `seconds` of wall time pass; returns whether done() became true.
template <class Done>
bool waitFor(Done&& done, double seconds) {
  const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(seconds);
  while (ros::ok() && ros::WallTime::now() < end) {
    ros::spinOnce();
    if (done()) return true;
    ros::WallDuration(0.01).sleep();
  }
  return false;
}

/// Calls a simulator's ~command service (start, pause, step, frame, reset) and expects it to succeed.
inline relaxed_connectivity::SimulationCommand::Response callCommand(ros::ServiceClient& client,
                                                                     const std::string& name,
                                                                     uint32_t steps = 0) {
  relaxed_connectivity::SimulationCommand c;
  c.request.command = name;
  c.request.steps = steps;
  EXPECT_TRUE(client.call(c)) << name;
  EXPECT_TRUE(c.response.success) << name << ": " << c.response.message;
  return c.response;
}

/// Calls a simulator's ~save (SaveState) for a .ply and returns the number of points read back from it (0 on
/// a failure, reported); a file with extension `bad_extension` must be refused with a message containing
/// `refusal_words`.
inline size_t savedPointCount(ros::NodeHandle& nh, const std::string& service,
                              const std::string& bad_extension, const std::string& refusal_words) {
  ros::ServiceClient save = nh.serviceClient<relaxed_connectivity::SaveState>(service);
  EXPECT_TRUE(save.waitForExistence(ros::Duration(10)));
  const std::string stem = "/tmp/rc_save_state_" + std::to_string(::getpid());
  relaxed_connectivity::SaveState state;
  state.request.path = stem + bad_extension;
  EXPECT_TRUE(save.call(state));
  EXPECT_FALSE(state.response.success);
  EXPECT_NE(state.response.message.find(refusal_words), std::string::npos) << state.response.message;
  state.request.path = stem + ".ply";
  EXPECT_TRUE(save.call(state));
  EXPECT_TRUE(state.response.success) << state.response.message;
  if (!state.response.success) return 0;
  const size_t count = readCloud(state.request.path).size();
  std::remove(state.request.path.c_str());
  return count;
}

/// config/rviz/<name>.rviz has the fixed frame "world" and shows `expected_displays` PointCloud2,
/// SurfelCloud or Marker topics, each of them advertised by somebody.
inline void expectRvizTopicsPublished(const std::string& rviz_path, int expected_displays) {
  const YAML::Node rviz = YAML::LoadFile(rviz_path);
  const YAML::Node manager = rviz["Visualization Manager"];
  ASSERT_TRUE(manager.IsMap());
  EXPECT_EQ(manager["Global Options"]["Fixed Frame"].as<std::string>(), "world");
  ros::master::V_TopicInfo topics;
  ASSERT_TRUE(waitFor(
      [&] { return ros::master::getTopics(topics) && int(topics.size()) > expected_displays; }, 10.0));
  int shown = 0;
  for (const auto& display : manager["Displays"]) {
    const std::string type = display["Class"].as<std::string>();
    std::string topic;
    if (type == "rviz/PointCloud2" || type == "relaxed_connectivity/SurfelCloud")
      topic = display["Topic"].as<std::string>();
    if (type == "rviz/Marker") topic = display["Marker Topic"].as<std::string>();
    if (topic.empty()) continue;
    ++shown;
    const bool published = std::any_of(topics.begin(), topics.end(),
                                       [&](const ros::master::TopicInfo& t) { return t.name == topic; });
    EXPECT_TRUE(published) << "rviz shows " << topic << ", which nobody publishes";
  }
  EXPECT_EQ(shown, expected_displays);
}

}  // namespace rc
