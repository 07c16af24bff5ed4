// diagnostic_updater status of a node (issue 23, like the ROS drivers' diagnostics): per input topic its
// message rate, accepted and rejected counts and the last rejection, and tasks the node adds (a loop's
// timing, a simulation's state). Published on /diagnostics by diagnostic_updater every diagnostic_period
// (default 1 s; rqt_runtime_monitor and rqt_robot_monitor show it).
#pragma once

#include <diagnostic_updater/diagnostic_updater.h>
#include <ros/ros.h>

#include <cstdint>
#include <functional>
#include <map>
#include <mutex>
#include <string>

namespace rc {

class NodeDiagnostics {
 public:
  /// Statuses are named "<node>: <task>" (the node or nodelet name from private_nh); hardware_id: what they
  /// belong to. Updates from a wall timer at 4 Hz.
  NodeDiagnostics(ros::NodeHandle nh, ros::NodeHandle private_nh, const std::string& hardware_id);

  /// An input topic's status: OK while messages arrive and none was rejected since the last report; WARN
  /// after a rejection (the reason is in the report) or when nothing came for stale_seconds after the first
  /// message (an input that never delivered is OK: "waiting"; stale_seconds 0: never stale, for latched
  /// inputs that come once).
  void addInput(const std::string& topic, double stale_seconds);
  /// Thread-safe; unknown topics are added with a stale time of 10 s.
  void accepted(const std::string& topic);
  void rejected(const std::string& topic, const std::string& reason);

  /// A status task of the node, called from the updater's thread.
  void addTask(const std::string& name,
               std::function<void(diagnostic_updater::DiagnosticStatusWrapper&)> task);

 private:
  struct Input {
    double stale_seconds = 10.0;
    uint64_t accepted = 0, rejected = 0;
    uint64_t reported_accepted = 0, reported_rejected = 0;  // at the previous report
    ros::WallTime last_message, last_report;
    std::string last_rejection;
  };
  void reportInput(const std::string& topic, diagnostic_updater::DiagnosticStatusWrapper& status);
  Input& input(const std::string& topic);  // with mutex_ held

  diagnostic_updater::Updater updater_;
  ros::WallTimer timer_;
  std::mutex mutex_;
  std::map<std::string, Input> inputs_;
};

}  // namespace rc
