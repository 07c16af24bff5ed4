// The shell_sim node (thesis 7): runs a thin-shell scene file (shell/shell_simulation.h, config/shell/*.yaml)
// frame by frame in real time, publishes the dense surfels, the nodes and the fibers for rviz, and pushes
// nodes with forces given by service.
//
// Publishes   ~surfels (sensor_msgs/PointCloud2, the deformed dense surfels,
// PointCloud2Layout::kPointSurfel),
//             ~cracks (sensor_msgs/PointCloud2, the crack discontinuity surfels), ~nodes
//             (visualization_msgs/Marker SPHERE_LIST, one point per node), ~fibers (visualization_msgs/Marker
//             LINE_LIST, end1-center and center-end2 per fiber), ~stats (relaxed_connectivity/ShellStats),
//             all in frame_id; ~probes (relaxed_connectivity/ShellProbes) with each frame when the scene has
//             probes (its key probes, as rc_shell writes them)
// Services    ~command (relaxed_connectivity/SimulationCommand: start | pause | step N (solver steps) |
//             frame N (frames) | reset; reset restores the scene at t = 0, paused, and drops the applied
//             forces), ~apply_force (relaxed_connectivity/ShellForce: a force on one node or on the nodes
//             near a point for a simulated duration; bad input is refused with a message and changes
//             nothing), ~hold (relaxed_connectivity/ShellHold: components of the nodes in a box held from now
//             on, until reset), ~save (relaxed_connectivity/SaveState: the deformed surfels as
//             .ply/.pcd/.xyz, crack surfels beside them)
// Parameters  (private) scene (file, required), frame_id, rate (frames per wall second: one frame per tick),
//             autostart, node_count (> 0 replaces the scene's node count, for speed); see
//             config/shell_demo.yaml.
// The scene file's frame count and outputs are ignored: the node runs until paused. A failing frame
// (ShellInstabilityError) resets the scene to t = 0, paused, and the stats' error says why.
#pragma once

#include <relaxed_connectivity/SaveState.h>
#include <relaxed_connectivity/ShellForce.h>
#include <relaxed_connectivity/ShellHold.h>
#include <relaxed_connectivity/SimulationCommand.h>
#include <ros/ros.h>
#include <std_msgs/Header.h>
#include <visualization_msgs/Marker.h>

#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "relaxed_connectivity/ros/simulation_loop.h"
#include "relaxed_connectivity/shell/shell_applied_force.h"
#include "relaxed_connectivity/shell/shell_simulation.h"

namespace rc {

struct ShellSimulatorParams {
  std::string scene;
  std::string frame_id = "world";
  double rate = 30.0;     ///< frames per wall-clock second while running
  bool autostart = true;  ///< run after loading (else paused at t = 0)
  int node_count = 0;     ///< > 0: replaces the scene's node count (nodes.count)

  /// Throws std::invalid_argument naming the parameter and the bad value.
  void validate() const;
};

ShellSimulatorParams readShellSimulatorParams(const ros::NodeHandle& private_nh);

/// The ShellForce request as a shellAppliedForce (errors as there).
ShellAppliedForce shellForceFromRequest(const relaxed_connectivity::ShellForce::Request& request,
                                        const std::vector<Vec3>& positions);

/// The nodes at `positions` as a SPHERE_LIST of diameter `size`; header and namespace are left to the caller.
visualization_msgs::Marker shellNodesMarker(const std::vector<Vec3>& positions, double size);
/// The fibers as a LINE_LIST (end1-center, center-end2: 4 points per fiber) of width `width`.
visualization_msgs::Marker shellFibersMarker(const ShellFibers& fibers, const std::vector<Vec3>& positions,
                                             double width);

class ShellSimulator {
 public:
  /// Reads the parameters and loads ~scene (throws std::invalid_argument / ShellSceneError).
  ShellSimulator(ros::NodeHandle nh, ros::NodeHandle private_nh);

  bool running() const { return loop_.running(); }

 private:
  SimulationLoopCallbacks loopCallbacks();
  /// Simulates `count` frames (or, with `steps`, solver steps) with the applied forces; a failure resets to
  /// t = 0, paused, and returns the error (empty: none).
  std::string advance(int count, bool steps = false);
  /// Adds the impulses of the applied forces for the next `interval` simulated seconds (F dt / m per node).
  void applyForces(double interval);
  void publish();
  /// The scene's probes on ~probes (relaxed_connectivity/ShellProbes), with each frame.
  void publishProbes(const std_msgs::Header& header);
  void resetSimulation();
  bool forceCallback(relaxed_connectivity::ShellForce::Request& request,
                     relaxed_connectivity::ShellForce::Response& response);
  /// ~save (relaxed_connectivity/SaveState): the current state to a file, the format by its extension.
  bool saveCallback(relaxed_connectivity::SaveState::Request& request,
                    relaxed_connectivity::SaveState::Response& response);
  bool holdCallback(relaxed_connectivity::ShellHold::Request& request,
                    relaxed_connectivity::ShellHold::Response& response);

  ros::NodeHandle nh_, private_nh_;
  ShellSimulatorParams params_;
  SimulationLoop loop_;  // timer, ~command, running, error, the mutex guarding the simulation
  ShellScene scene_;
  std::unique_ptr<ShellSimulation> simulation_;
  std::vector<std::vector<uint32_t>> probe_nodes_;  // the nodes of each of the scene's probes
  std::vector<ShellAppliedForce> forces_;
  ShellFrameReport last_frame_;
  double node_size_ = 0.0;  ///< marker size: a quarter of the mean rest fiber length
  ros::Publisher surfels_pub_, cracks_pub_, nodes_pub_, fibers_pub_, stats_pub_, probes_pub_;
  ros::ServiceServer force_srv_, hold_srv_, save_srv_;
};

}  // namespace rc
