// The real-time loop every simulator node shares (sph_sim, fem_sim, shell_sim; the haptic driver later): a
// wall timer that advances a running simulation by one tick and then publishes, the start / pause / step /
// frame / reset commands of ~command (SimulationCommand.srv), the error that stops a run, and the mutex that
// guards the simulation against the timer and service calls. The node says what a tick, a step and a reset
// are.
#pragma once

#include <ros/ros.h>

#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <string>

#include "relaxed_connectivity/SimulationCommand.h"
#include "relaxed_connectivity/ros/node_diagnostics.h"

namespace rc {

/// What a node does inside the loop. All but `publish` are called with the loop's mutex held.
struct SimulationLoopCallbacks {
  /// Whether a simulation is loaded (null: always); commands fail with `not_ready_message` otherwise.
  std::function<bool()> ready;
  std::string not_ready_message = "no scene loaded";
  /// Advances a running simulation by one timer tick (e.g. real_time_factor / rate simulated seconds, or one
  /// frame); returns the error that stops the run, empty when fine.
  std::function<std::string()> tick;
  /// Advances by `count` >= 1 solver steps; same return.
  std::function<std::string(uint32_t count)> step;
  /// Advances by `count` >= 1 frames of the scene (its output frames: steps_per_frame steps or frame_time
  /// seconds); same return.
  std::function<std::string(uint32_t count)> frame;
  /// Where the simulation is, for messages ("step 12, t = 0.0400 s").
  std::function<std::string()> where;
  /// Back to the scene's start; returns the message ("reset to t = 0: 8 bodies").
  std::function<std::string()> reset;
  /// Publishes the state (after a tick and after every command); stamps with SimulationLoop::stamp().
  std::function<void()> publish;
  /// Simulated seconds since the scene's start (for ~publish_clock and stamp()); called with the mutex held.
  std::function<double()> time;
  /// true: after an error the state is kept for inspection and start / step refuse until a reset (SPH
  /// instability); false: the node has already reset the simulation and start / step clear the error.
  bool error_needs_reset = false;
};

class SimulationLoop {
 public:
  /// `name`: the node's name in log lines.
  SimulationLoop(std::string name, SimulationLoopCallbacks callbacks);

  /// Advertises ~command on `private_nh` and starts the wall timer at `rate` ticks per second (> 0). With the
  /// private parameter publish_clock (default false) the simulated time goes out on /clock
  /// (rosgraph_msgs/Clock) after every tick and command, and stamp() gives it, so a recorded simulation
  /// replays in simulated time. Reports the simulation on /diagnostics (running or paused and where; ERROR
  /// with the error that stopped a run).
  void start(ros::NodeHandle nh, ros::NodeHandle private_nh, double rate);
  /// The stamp of published messages: the simulated time with publish_clock, else the ROS time now. Call
  /// with the mutex held.
  ros::Time stamp() const;
  bool publishesClock() const { return publish_clock_; }

  std::mutex& mutex() { return mutex_; }
  bool running() const { return running_; }
  void setRunning(bool running) { running_ = running; }
  /// The error that stopped the run (empty: none).
  const std::string& error() const { return error_; }
  /// Stops the run with `error` (logged); empty: clears it.
  void setError(const std::string& error);

  /// The command's result (what the ~command service answers); the mutex must not be held.
  void command(const relaxed_connectivity::SimulationCommand::Request& request,
               relaxed_connectivity::SimulationCommand::Response& response);

 private:
  void timerCallback(const ros::WallTimerEvent&);
  bool commandCallback(relaxed_connectivity::SimulationCommand::Request& request,
                       relaxed_connectivity::SimulationCommand::Response& response);

  std::string name_;
  SimulationLoopCallbacks callbacks_;
  std::mutex mutex_;
  bool running_ = false;
  std::string error_;
  void publishClock();  // with the mutex held
  ros::ServiceServer command_srv_;
  bool publish_clock_ = false;
  ros::Publisher clock_pub_;
  std::unique_ptr<NodeDiagnostics> diagnostics_;
  ros::WallTimer timer_;
};

}  // namespace rc
