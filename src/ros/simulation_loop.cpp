#include "relaxed_connectivity/ros/simulation_loop.h"

#include <diagnostic_msgs/DiagnosticStatus.h>
#include <rosgraph_msgs/Clock.h>

#include <algorithm>
#include <stdexcept>

#include "relaxed_connectivity/ros/simulation_commands.h"

namespace rc {

SimulationLoop::SimulationLoop(std::string name, SimulationLoopCallbacks callbacks)
    : name_(std::move(name)), callbacks_(std::move(callbacks)) {
  if (!callbacks_.tick || !callbacks_.step || !callbacks_.frame || !callbacks_.where || !callbacks_.reset ||
      !callbacks_.publish || !callbacks_.time)
    throw std::invalid_argument(name_ +
                                ": SimulationLoop needs tick, step, frame, where, reset, publish and time");
}

void SimulationLoop::start(ros::NodeHandle nh, ros::NodeHandle private_nh, double rate) {
  if (!(rate > 0)) throw std::invalid_argument(name_ + ": rate must be > 0 Hz");
  command_srv_ = private_nh.advertiseService("command", &SimulationLoop::commandCallback, this);
  private_nh.param("publish_clock", publish_clock_, false);
  if (publish_clock_) clock_pub_ = nh.advertise<rosgraph_msgs::Clock>("/clock", 10);
  diagnostics_ = std::make_unique<NodeDiagnostics>(nh, private_nh, name_);
  diagnostics_->addTask("simulation", [this](diagnostic_updater::DiagnosticStatusWrapper& status) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (callbacks_.ready && !callbacks_.ready()) {
      status.summary(diagnostic_msgs::DiagnosticStatus::OK, callbacks_.not_ready_message);
      return;
    }
    status.add("where", callbacks_.where());
    status.add("running", running_);
    if (!error_.empty())
      status.summary(diagnostic_msgs::DiagnosticStatus::ERROR, error_);
    else
      status.summary(diagnostic_msgs::DiagnosticStatus::OK,
                     (running_ ? "running, " : "paused, ") + callbacks_.where());
  });
  timer_ = nh.createWallTimer(ros::WallDuration(1.0 / rate), &SimulationLoop::timerCallback, this);
}

void SimulationLoop::setError(const std::string& error) {
  error_ = error;
  if (error.empty()) return;
  running_ = false;
  ROS_ERROR_STREAM(name_ << ": " << error);
}

ros::Time SimulationLoop::stamp() const {
  if (!publish_clock_) return ros::Time::now();
  const double t = callbacks_.ready && !callbacks_.ready() ? 0.0 : callbacks_.time();
  return ros::Time(std::max(0.0, t));
}

void SimulationLoop::publishClock() {
  if (!publish_clock_) return;
  rosgraph_msgs::Clock clock;
  clock.clock = stamp();
  clock_pub_.publish(clock);
}

void SimulationLoop::timerCallback(const ros::WallTimerEvent&) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!running_ || (callbacks_.ready && !callbacks_.ready())) return;
    setError(callbacks_.tick());
    publishClock();
  }
  callbacks_.publish();
}

void SimulationLoop::command(const relaxed_connectivity::SimulationCommand::Request& request,
                             relaxed_connectivity::SimulationCommand::Response& response) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (callbacks_.ready && !callbacks_.ready()) {
      response.success = false;
      response.message = callbacks_.not_ready_message;
      return;
    }
    // With error_needs_reset an error keeps the state for inspection: only pause and reset go on.
    auto blocked = [&] { return callbacks_.error_needs_reset && !error_.empty(); };
    SimulationCommandHandlers handlers;
    handlers.start = [&]() -> CommandResult {
      if (blocked()) return {false, error_ + " at " + callbacks_.where() + ": reset first"};
      error_.clear();
      running_ = true;
      return {true, "running"};
    };
    handlers.pause = [&]() -> CommandResult {
      running_ = false;
      return {true, "paused at " + callbacks_.where()};
    };
    auto advance = [&](const std::function<std::string(uint32_t)>& by, uint32_t count) -> CommandResult {
      running_ = false;
      if (blocked()) return {false, error_ + " at " + callbacks_.where() + ": reset first"};
      error_.clear();
      setError(by(count));
      if (!error_.empty()) return {false, error_};
      return {true, callbacks_.where()};
    };
    handlers.step = [&](uint32_t count) { return advance(callbacks_.step, count); };
    handlers.frame = [&](uint32_t count) { return advance(callbacks_.frame, count); };
    handlers.reset = [&]() -> CommandResult {
      running_ = false;
      error_.clear();
      return {true, callbacks_.reset()};
    };
    dispatchSimulationCommand(request, response, handlers);
    publishClock();
  }
  callbacks_.publish();
}

bool SimulationLoop::commandCallback(relaxed_connectivity::SimulationCommand::Request& request,
                                     relaxed_connectivity::SimulationCommand::Response& response) {
  command(request, response);
  return true;
}

}  // namespace rc
