// The sph_sim node (thesis 8): runs an SPH scene file (sph/sph_simulation.h, config/sph/*.yaml) in real time
// and publishes the particles for rviz; start, pause, single steps, reset and scene loading by service. Each
// step runs the scene's temperature, melting / freezing and fluid sources as rc_sph does (SphSimulation).
//
// Publishes   ~particles (sensor_msgs/PointCloud2: x y z, velocity[3], density, pressure (float32), kind
//             (uint8: 0 fluid, 1 static boundary, 2 moving boundary); scenes with temperature add
//             temperature (float32) and phase (uint8: 0 fluid, else the solid's id)), ~surface
//             (visualization_msgs/Marker, TRIANGLE_LIST of the fluid surface, 8.2.7; only with ~surface
//             true), ~stats (relaxed_connectivity/SphStats), ~probes (relaxed_connectivity/SphProbes:
//             the liquid's measures and density and pressure at points, for scenes with the key probes), all
//             in frame_id
// Services    ~command (relaxed_connectivity/SimulationCommand: start | pause | step N (solver steps) |
//             frame N (frame_time each) | reset),
//             ~load_scene (relaxed_connectivity/LoadSphScene; a bad file is reported and changes nothing),
//             ~save (relaxed_connectivity/SaveState: the particles as .ply or .vtp)
// Parameters  (private) scene (file; empty: wait for ~load_scene), frame_id, rate (frames per second),
//             autostart, real_time_factor (simulated seconds per wall second), surface, surface_cell_size
//             (0: h / 2), threads; see config/sph_demo.yaml.
#pragma once

#include <relaxed_connectivity/LoadSphScene.h>
#include <relaxed_connectivity/SaveState.h>
#include <relaxed_connectivity/SimulationCommand.h>
#include <ros/ros.h>

#include <memory>
#include <mutex>
#include <string>

#include "relaxed_connectivity/ros/simulation_loop.h"
#include "relaxed_connectivity/sph/sph_fluid_solver.h"
#include "relaxed_connectivity/sph/sph_scene.h"
#include "relaxed_connectivity/sph/sph_simulation.h"

namespace rc {

struct SphSimulatorParams {
  std::string scene;
  std::string frame_id = "world";
  double rate = 30.0;              ///< published frames per second
  bool autostart = true;           ///< run after loading (else paused at t = 0)
  double real_time_factor = 1.0;   ///< simulated seconds per wall-clock second while running
  bool surface = false;            ///< publish the fluid surface mesh
  double surface_cell_size = 0.0;  ///< marching cubes cell [m]; 0: h / 2
  int threads = 0;                 ///< solver threads, 0: all

  /// Throws std::invalid_argument naming the parameter and the bad value.
  void validate() const;
};

SphSimulatorParams readSphSimulatorParams(const ros::NodeHandle& private_nh);

class SphSimulator {
 public:
  /// Reads the parameters and loads ~scene if given (throws std::invalid_argument / SphSceneError).
  SphSimulator(ros::NodeHandle nh, ros::NodeHandle private_nh);

  /// Loads a scene; on failure returns false with the error in *message and keeps the current state.
  bool load(const std::string& path, bool start, std::string* message);
  bool running() const { return loop_.running(); }

 private:
  SimulationLoopCallbacks loopCallbacks();
  /// Advances by up to `steps` steps or `duration` simulated seconds (whichever ends first); pauses and
  /// returns the instability that stopped it (empty: none).
  std::string advance(double duration, uint64_t steps);
  void publish();
  /// ~save (relaxed_connectivity/SaveState): the current state to a file, the format by its extension.
  bool saveCallback(relaxed_connectivity::SaveState::Request& request,
                    relaxed_connectivity::SaveState::Response& response);
  bool loadCallback(relaxed_connectivity::LoadSphScene::Request& request,
                    relaxed_connectivity::LoadSphScene::Response& response);

  ros::NodeHandle nh_, private_nh_;
  SphSimulatorParams params_;
  SimulationLoop loop_;  // timer, ~command, running, instability, the mutex guarding scene and simulation
  std::unique_ptr<SphScene> scene_;
  std::unique_ptr<SphSimulation> simulation_;  // solver, temperature, phase changes, sources
  double step_ms_ = 0.0;
  ros::Publisher particles_pub_, surface_pub_, stats_pub_, probes_pub_;
  ros::ServiceServer load_srv_, save_srv_;
};

}  // namespace rc
