#include "relaxed_connectivity/ros/node_diagnostics.h"

#include <diagnostic_msgs/DiagnosticStatus.h>

namespace rc {

NodeDiagnostics::NodeDiagnostics(ros::NodeHandle nh, ros::NodeHandle private_nh,
                                 const std::string& hardware_id)
    : updater_(nh, private_nh, private_nh.getNamespace()) {  // statuses named "<node>: <task>"
  updater_.setHardwareID(hardware_id);
  timer_ =
      nh.createWallTimer(ros::WallDuration(0.25), [this](const ros::WallTimerEvent&) { updater_.update(); });
}

NodeDiagnostics::Input& NodeDiagnostics::input(const std::string& topic) {
  auto it = inputs_.find(topic);
  if (it != inputs_.end()) return it->second;
  Input& added = inputs_[topic];
  added.last_report = ros::WallTime::now();
  updater_.add("input " + topic, [this, topic](diagnostic_updater::DiagnosticStatusWrapper& status) {
    reportInput(topic, status);
  });
  return added;
}

void NodeDiagnostics::addInput(const std::string& topic, double stale_seconds) {
  std::lock_guard<std::mutex> lock(mutex_);
  input(topic).stale_seconds = stale_seconds;
}

void NodeDiagnostics::accepted(const std::string& topic) {
  std::lock_guard<std::mutex> lock(mutex_);
  Input& in = input(topic);
  ++in.accepted;
  in.last_message = ros::WallTime::now();
}

void NodeDiagnostics::rejected(const std::string& topic, const std::string& reason) {
  std::lock_guard<std::mutex> lock(mutex_);
  Input& in = input(topic);
  ++in.rejected;
  in.last_message = ros::WallTime::now();
  in.last_rejection = reason;
}

void NodeDiagnostics::addTask(const std::string& name,
                              std::function<void(diagnostic_updater::DiagnosticStatusWrapper&)> task) {
  updater_.add(name, std::move(task));
}

void NodeDiagnostics::reportInput(const std::string& topic,
                                  diagnostic_updater::DiagnosticStatusWrapper& status) {
  std::lock_guard<std::mutex> lock(mutex_);
  Input& in = inputs_[topic];
  const ros::WallTime now = ros::WallTime::now();
  const double window = std::max(1e-6, (now - in.last_report).toSec());
  const uint64_t new_accepted = in.accepted - in.reported_accepted,
                 new_rejected = in.rejected - in.reported_rejected;
  const double rate = double(new_accepted + new_rejected) / window;
  status.add("rate [Hz]", rate);
  status.add("accepted", in.accepted);
  status.add("rejected", in.rejected);
  status.add("last rejection", in.last_rejection);
  const bool started = in.accepted + in.rejected > 0;
  const double idle = started ? (now - in.last_message).toSec() : 0.0;
  if (new_rejected > 0)
    status.summaryf(diagnostic_msgs::DiagnosticStatus::WARN, "%llu messages rejected: %s",
                    static_cast<unsigned long long>(new_rejected), in.last_rejection.c_str());
  else if (!started)
    status.summary(diagnostic_msgs::DiagnosticStatus::OK, "waiting for the first message");
  else if (in.stale_seconds > 0 && idle > in.stale_seconds)
    status.summaryf(diagnostic_msgs::DiagnosticStatus::WARN, "no message for %.1f s", idle);
  else
    status.summaryf(diagnostic_msgs::DiagnosticStatus::OK, "%.1f messages/s", rate);
  in.reported_accepted = in.accepted;
  in.reported_rejected = in.rejected;
  in.last_report = now;
}

}  // namespace rc
