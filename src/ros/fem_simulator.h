// The fem_sim node (thesis 9): runs an FEM scene file (fem/fem_simulation.h, config/fem/*.yaml) in real time,
// publishes the bodies for rviz and cuts them with polygons given by service.
//
// Publishes   ~surface (visualization_msgs/Marker, TRIANGLE_LIST of the boundary triangles of all bodies at
//             their current positions, coloured by body), ~nodes (sensor_msgs/PointCloud2: x y z,
//             velocity[3], displacement[3] (float32), body (uint32)), ~stats (relaxed_connectivity/FemStats),
//             all in frame_id (the scene's frame); ~probes (relaxed_connectivity/FemProbes) with each frame
//             when the scene has probes (its key probes, as rc_fem writes them)
// Services    ~command (relaxed_connectivity/SimulationCommand: start | pause | step N (solver steps) |
//             frame N (steps_per_frame steps each) | reset; reset
// restores the
//             scene file's mesh at t = 0, paused), ~cut (relaxed_connectivity/FemCut: a convex planar polygon
//             in any tf2 frame, applied to the rest configuration: the crossed elements it overlaps are
//             split by its plane (FemSimulation::applyCut with a region) or, progressive, the polygon itself
//             cuts (FemSimulation::applyPolygonCuts); a refused cut is reported and changes nothing), ~load
//             (relaxed_connectivity/FemLoad: a constant force spread over the nodes in a box, or a traction
//             on the boundary faces in it, added to the loads or replacing them, until reset), ~hold
//             (relaxed_connectivity/FemHold: components of the nodes in a box held in place, at a
//             displacement or along a path, added to the held regions or replacing them, until reset), ~save
//             (relaxed_connectivity/SaveState: the bodies as .vtu, .obj or the nodes as .ply/.pcd/.xyz)
// Parameters  (private) scene (file, required), frame_id, rate (frames per second), autostart,
//             real_time_factor (simulated seconds per wall second), tf_timeout (s),
//             planarity_tolerance (relative to the polygon's diameter); see config/fem_demo.yaml.
// The scene file's frame count is ignored: the node runs until paused. Its scheduled cuts are applied when
// their time comes (again after a reset). A failing step or scheduled cut resets the scene to t = 0, paused,
// and the stats' error says why.
#pragma once

#include <relaxed_connectivity/FemCut.h>
#include <relaxed_connectivity/FemHold.h>
#include <relaxed_connectivity/FemLoad.h>
#include <relaxed_connectivity/SaveState.h>
#include <relaxed_connectivity/SimulationCommand.h>
#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>
#include <visualization_msgs/Marker.h>

#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "relaxed_connectivity/core/surfel_cloud.h"
#include "relaxed_connectivity/fem/fem_cut_polygon.h"
#include "relaxed_connectivity/fem/fem_output.h"
#include "relaxed_connectivity/fem/fem_simulation.h"
#include "relaxed_connectivity/ros/simulation_loop.h"

namespace rc {

struct FemSimulatorParams {
  std::string scene;
  std::string frame_id = "world";
  double rate = 30.0;                 ///< published frames per second
  bool autostart = true;              ///< run after loading (else paused at t = 0)
  double real_time_factor = 1.0;      ///< simulated seconds per wall-clock second while running
  double tf_timeout = 0.5;            ///< s to wait for the transform of a cut polygon
  double planarity_tolerance = 1e-6;  ///< max distance of a polygon point from its plane / polygon diameter

  /// Throws std::invalid_argument naming the parameter and the bad value.
  void validate() const;
};

FemSimulatorParams readFemSimulatorParams(const ros::NodeHandle& private_nh);

/// The boundary triangles of all bodies at their current positions as one TRIANGLE_LIST marker (3 points
/// per triangle, one colour per vertex by body). Header and namespace are left to the caller.
visualization_msgs::Marker femSurfaceMarker(const std::vector<FemBodyState>& bodies);

class FemSimulator {
 public:
  /// Reads the parameters and loads ~scene (throws std::invalid_argument / FemSceneError).
  FemSimulator(ros::NodeHandle nh, ros::NodeHandle private_nh);

  bool running() const { return loop_.running(); }

 private:
  SimulationLoopCallbacks loopCallbacks();
  /// Advances by up to `steps` steps or `duration` simulated seconds (whichever ends first); a failing step
  /// resets to t = 0, paused, and returns the error (empty: none).
  std::string advance(double duration, uint64_t steps);
  void publish();
  /// The scene's probes on ~probes (relaxed_connectivity/FemProbes), with each frame.
  void publishProbes(const std_msgs::Header& header);
  void resetSimulation();
  bool loadCallback(relaxed_connectivity::FemLoad::Request& request,
                    relaxed_connectivity::FemLoad::Response& response);
  /// ~save (relaxed_connectivity/SaveState): the current state to a file, the format by its extension.
  bool saveCallback(relaxed_connectivity::SaveState::Request& request,
                    relaxed_connectivity::SaveState::Response& response);
  bool holdCallback(relaxed_connectivity::FemHold::Request& request,
                    relaxed_connectivity::FemHold::Response& response);
  bool cutCallback(relaxed_connectivity::FemCut::Request& request,
                   relaxed_connectivity::FemCut::Response& response);
  /// The polygon of a request in the scene frame (throws std::invalid_argument / std::runtime_error).
  std::vector<Vec3> polygonInSceneFrame(const relaxed_connectivity::FemCut::Request& request);

  ros::NodeHandle nh_, private_nh_;
  FemSimulatorParams params_;
  tf2_ros::Buffer tf_buffer_;
  tf2_ros::TransformListener tf_listener_;
  SimulationLoop loop_;  // timer, ~command, running, error, the mutex guarding the simulation
  std::unique_ptr<FemScene> scene_;
  std::unique_ptr<FemSimulation> simulation_;
  double probe_tolerance_ = 0.0;  // of the scene's probe boxes (femBoxTolerance of its rest mesh)
  int interactive_cuts_ = 0;
  double step_ms_ = 0.0;
  ros::Publisher surface_pub_, nodes_pub_, stats_pub_, probes_pub_;
  ros::ServiceServer cut_srv_, load_srv_, hold_srv_, save_srv_;
};

}  // namespace rc
