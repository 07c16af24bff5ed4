#include "relaxed_connectivity/ros/shell_simulator.h"

#include <relaxed_connectivity/ShellProbes.h>
#include <relaxed_connectivity/ShellStats.h>
#include <sensor_msgs/PointCloud2.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <stdexcept>

#include "relaxed_connectivity/io/cloud_io.h"
#include "relaxed_connectivity/ros/point_cloud2_converter.h"
#include "relaxed_connectivity/ros/simulation_loop.h"
#include "relaxed_connectivity/shell/shell_probes.h"
#include "relaxed_connectivity/shell/shell_scene_reader.h"
#include "relaxed_connectivity/shell/shell_scene_regions.h"

namespace rc {

void ShellSimulatorParams::validate() const {
  auto fail = [](const std::string& what) { throw std::invalid_argument("shell_sim: " + what); };
  if (scene.empty()) fail("parameter ~scene (a shell scene file, config/shell/*.yaml) is required");
  if (frame_id.empty() || frame_id[0] == '/')
    fail("frame_id '" + frame_id + "' must be non-empty without '/'");
  if (!(rate > 0) || !std::isfinite(rate)) fail("rate must be > 0 Hz (got " + std::to_string(rate) + ")");
  if (node_count < 0)
    fail("node_count must be >= 0 (0: the scene's; got " + std::to_string(node_count) + ")");
}

ShellSimulatorParams readShellSimulatorParams(const ros::NodeHandle& pnh) {
  ShellSimulatorParams p;
  pnh.param("scene", p.scene, p.scene);
  pnh.param("frame_id", p.frame_id, p.frame_id);
  pnh.param("rate", p.rate, p.rate);
  pnh.param("autostart", p.autostart, p.autostart);
  pnh.param("node_count", p.node_count, p.node_count);
  p.validate();
  return p;
}

ShellAppliedForce shellForceFromRequest(const relaxed_connectivity::ShellForce::Request& request,
                                        const std::vector<Vec3>& positions) {
  return shellAppliedForce(Vec3(request.force.x, request.force.y, request.force.z), request.duration,
                           request.node, Vec3(request.point.x, request.point.y, request.point.z),
                           request.radius, positions);
}

namespace {

geometry_msgs::Point toPoint(const Vec3& p) {
  geometry_msgs::Point point;
  point.x = p.x();
  point.y = p.y();
  point.z = p.z();
  return point;
}

}  // namespace

visualization_msgs::Marker shellNodesMarker(const std::vector<Vec3>& positions, double size) {
  visualization_msgs::Marker marker;
  marker.type = visualization_msgs::Marker::SPHERE_LIST;
  marker.action = visualization_msgs::Marker::ADD;
  marker.pose.orientation.w = 1.0;
  marker.scale.x = marker.scale.y = marker.scale.z = size;
  marker.color.r = 0.95f;
  marker.color.g = 0.45f;
  marker.color.b = 0.15f;
  marker.color.a = 1.0f;
  marker.points.reserve(positions.size());
  for (const Vec3& p : positions) marker.points.push_back(toPoint(p));
  return marker;
}

visualization_msgs::Marker shellFibersMarker(const ShellFibers& fibers, const std::vector<Vec3>& positions,
                                             double width) {
  visualization_msgs::Marker marker;
  marker.type = visualization_msgs::Marker::LINE_LIST;
  marker.action = visualization_msgs::Marker::ADD;
  marker.pose.orientation.w = 1.0;
  marker.scale.x = width;
  marker.color.r = 0.3f;
  marker.color.g = 0.6f;
  marker.color.b = 0.9f;
  marker.color.a = 1.0f;
  marker.points.reserve(4 * fibers.size());
  for (const Fiber& f : fibers.fibers) {
    marker.points.push_back(toPoint(positions.at(f.end1)));
    marker.points.push_back(toPoint(positions.at(f.center)));
    marker.points.push_back(toPoint(positions.at(f.center)));
    marker.points.push_back(toPoint(positions.at(f.end2)));
  }
  return marker;
}

ShellSimulator::ShellSimulator(ros::NodeHandle nh, ros::NodeHandle private_nh)
    : nh_(nh),
      private_nh_(private_nh),
      params_(readShellSimulatorParams(private_nh)),
      loop_("shell_sim", loopCallbacks()) {
  surfels_pub_ = private_nh_.advertise<sensor_msgs::PointCloud2>("surfels", 1);
  cracks_pub_ = private_nh_.advertise<sensor_msgs::PointCloud2>("cracks", 1);
  nodes_pub_ = private_nh_.advertise<visualization_msgs::Marker>("nodes", 1);
  fibers_pub_ = private_nh_.advertise<visualization_msgs::Marker>("fibers", 1);
  stats_pub_ = private_nh_.advertise<relaxed_connectivity::ShellStats>("stats", 1);
  probes_pub_ = private_nh_.advertise<relaxed_connectivity::ShellProbes>("probes", 10);
  scene_ = loadShellScene(params_.scene);
  if (scene_.analysis != ShellAnalysis::kDynamic)
    throw std::invalid_argument(
        params_.scene +
        ": analysis static and modal run with rc_shell (its JSON and frames); shell_sim "
        "runs dynamic scenes");
  if (params_.node_count > 0) {
    scene_.nodes.spacing = 0.0;
    scene_.nodes.target_count = size_t(params_.node_count);
  }
  scene_.output.every = 0;
  simulation_ = std::make_unique<ShellSimulation>(scene_);
  for (size_t k = 0; k < scene_.probes.size(); ++k)  // throws naming a box without nodes
    probe_nodes_.push_back(shellNodesInBox(simulation_->solver().nodes(), scene_.probes[k].lo,
                                           scene_.probes[k].hi,
                                           params_.scene + ": probes[" + std::to_string(k) + "]"));
  const ShellFibers& fibers = simulation_->solver().fibers();
  double length = 0.0;
  for (const Fiber& f : fibers.fibers) length += f.rest_length;
  node_size_ = fibers.size() > 0 ? 0.25 * length / double(fibers.size()) : 0.01;
  loop_.setRunning(params_.autostart);
  ROS_INFO_STREAM("shell_sim: loaded " << params_.scene << ": " << simulation_->solver().nodes().size()
                                       << " nodes, " << simulation_->fiberCount() << " fibers, "
                                       << simulation_->surfels().size() << " surfels");
  force_srv_ = private_nh_.advertiseService("apply_force", &ShellSimulator::forceCallback, this);
  hold_srv_ = private_nh_.advertiseService("hold", &ShellSimulator::holdCallback, this);
  save_srv_ = private_nh_.advertiseService("save", &ShellSimulator::saveCallback, this);
  loop_.start(nh_, private_nh_, params_.rate);
}

SimulationLoopCallbacks ShellSimulator::loopCallbacks() {
  SimulationLoopCallbacks c;
  c.tick = [this] { return advance(1); };  // one frame per tick
  c.step = [this](uint32_t steps) { return advance(int(std::min<uint32_t>(steps, 1000000)), true); };
  c.frame = [this](uint32_t frames) { return advance(int(std::min<uint32_t>(frames, 1000000))); };
  c.where = [this] {
    return "frame " + std::to_string(simulation_->frame()) +
           ", t = " + std::to_string(simulation_->solver().time()) + " s";
  };
  c.reset = [this] {
    resetSimulation();
    return "reset to t = 0: " + std::to_string(simulation_->solver().nodes().size()) + " nodes, " +
           std::to_string(simulation_->surfels().size()) + " surfels";
  };
  c.publish = [this] { publish(); };
  c.time = [this] { return simulation_->solver().time(); };
  return c;
}

void ShellSimulator::resetSimulation() {
  simulation_ = std::make_unique<ShellSimulation>(scene_);
  forces_.clear();
  last_frame_ = ShellFrameReport();
  loop_.setRunning(false);
  loop_.setError("");
}

void ShellSimulator::applyForces(double interval) {
  if (forces_.empty() || !(interval > 0)) return;  // (an adaptive step before the first frame: next frame)
  ShellSolver& solver = simulation_->mutableSolver();
  const std::vector<double>& masses = solver.energy().masses();
  std::vector<Vec3> velocities = solver.velocities();
  for (ShellAppliedForce& applied : forces_) {
    const double duration = std::min(applied.remaining, interval);
    for (size_t i : applied.nodes) velocities[i] += applied.force * (duration / masses[i]);
    applied.remaining -= duration;
  }
  solver.setVelocities(velocities);  // pinned nodes stay at rest; the impulse counts as available energy
  forces_.erase(std::remove_if(forces_.begin(), forces_.end(),
                               [](const ShellAppliedForce& f) { return !(f.remaining > 0); }),
                forces_.end());
}

std::string ShellSimulator::advance(int count, bool steps) {
  const double dt = last_frame_.dt > 0 ? last_frame_.dt : scene_.solver.time_step;
  const double frame_time = scene_.frame_time > 0 ? scene_.frame_time : scene_.steps_per_frame * dt;
  for (int k = 0; k < count; ++k) {
    try {
      applyForces(steps ? dt : frame_time);
      last_frame_ = steps ? simulation_->advanceSteps(1) : simulation_->advanceFrame();
    } catch (const std::exception& e) {
      const std::string what = e.what();
      resetSimulation();
      return what + " (reset to t = 0, paused)";
    }
  }
  return std::string();
}

void ShellSimulator::publish() {
  std::lock_guard<std::mutex> lock(loop_.mutex());
  const ros::Time stamp = loop_.stamp();
  const ShellSolver& solver = simulation_->solver();
  if (surfels_pub_.getNumSubscribers() > 0) {
    SurfelCloud cloud = simulation_->surfels();
    cloud.frame_id = params_.frame_id;
    cloud.stamp_ns = stamp.toNSec();
    surfels_pub_.publish(PointCloud2Converter::toMessage(cloud));
  }
  if (cracks_pub_.getNumSubscribers() > 0) {
    SurfelCloud cloud = simulation_->crackSurfels();
    cloud.frame_id = params_.frame_id;
    cloud.stamp_ns = stamp.toNSec();
    cracks_pub_.publish(PointCloud2Converter::toMessage(cloud));
  }
  if (nodes_pub_.getNumSubscribers() > 0) {
    visualization_msgs::Marker marker = shellNodesMarker(solver.positions(), node_size_);
    marker.header.frame_id = params_.frame_id;
    marker.header.stamp = stamp;
    marker.ns = "shell_nodes";
    nodes_pub_.publish(marker);
  }
  if (fibers_pub_.getNumSubscribers() > 0) {
    visualization_msgs::Marker marker =
        shellFibersMarker(solver.fibers(), solver.positions(), 0.2 * node_size_);
    marker.header.frame_id = params_.frame_id;
    marker.header.stamp = stamp;
    marker.ns = "shell_fibers";
    fibers_pub_.publish(marker);
  }
  relaxed_connectivity::ShellStats stats;
  stats.header.frame_id = params_.frame_id;
  stats.header.stamp = stamp;
  stats.scene = scene_.name;
  stats.running = loop_.running();
  stats.frame = uint32_t(simulation_->frame());
  stats.step = uint64_t(solver.stepCount());
  stats.time = solver.time();
  stats.dt = last_frame_.dt;
  stats.pressure = last_frame_.pressure;
  stats.nodes = uint32_t(solver.nodes().size());
  stats.fibers = uint32_t(simulation_->fiberCount());
  stats.surfels = uint32_t(simulation_->surfels().size());
  stats.crack_surfels = uint32_t(simulation_->crackSurfels().size());
  stats.cracks = uint32_t(simulation_->crackCount());
  stats.active_forces = uint32_t(forces_.size());
  stats.mean_radius = simulation_->meanRadius();
  stats.max_speed = simulation_->maxSpeed();
  stats.forces_ms = last_frame_.forces_ms;
  stats.material_ms = last_frame_.material_ms;
  stats.surface_ms = last_frame_.surface_ms;
  stats.error = loop_.error();
  stats_pub_.publish(stats);
  if (!probe_nodes_.empty()) publishProbes(stats.header);
}

void ShellSimulator::publishProbes(const std_msgs::Header& header) {
  // The scene's probes (its key probes), as rc_shell writes them per frame.
  const ShellSolver& solver = simulation_->solver();
  const ShellMeasures all = measureShell(solver);
  relaxed_connectivity::ShellProbes probes;
  probes.header = header;
  probes.scene = scene_.name;
  probes.time = solver.time();
  probes.mass = all.mass;
  probes.kinetic_energy = all.kinetic_energy;
  probes.membrane_energy = all.membrane_energy;
  probes.bending_energy = all.bending_energy;
  probes.gravity_potential_energy = all.gravity_potential_energy;
  probes.momentum.x = all.momentum.x(), probes.momentum.y = all.momentum.y(),
  probes.momentum.z = all.momentum.z();
  auto vector3 = [](const Vec3& v) {
    geometry_msgs::Vector3 m;
    m.x = v.x(), m.y = v.y(), m.z = v.z();
    return m;
  };
  for (size_t k = 0; k < probe_nodes_.size(); ++k) {
    const ShellRegionMeasures m = measureShellRegion(solver, probe_nodes_[k]);
    probes.names.push_back(scene_.probes[k].name);
    probes.nodes.push_back(uint32_t(m.nodes));
    probes.masses.push_back(m.mass);
    probes.mean_displacements.push_back(vector3(m.mean_displacement));
    probes.max_displacements.push_back(m.max_displacement);
    probes.reactions.push_back(vector3(m.reaction));
  }
  probes_pub_.publish(probes);
}

bool ShellSimulator::forceCallback(relaxed_connectivity::ShellForce::Request& request,
                                   relaxed_connectivity::ShellForce::Response& response) {
  std::lock_guard<std::mutex> lock(loop_.mutex());
  try {
    ShellAppliedForce applied = shellForceFromRequest(request, simulation_->solver().positions());
    response.nodes = uint32_t(applied.nodes.size());
    forces_.push_back(std::move(applied));
    response.success = true;
    response.message = "force on " + std::to_string(response.nodes) + " nodes for " +
                       std::to_string(request.duration) + " s";
  } catch (const std::exception& e) {
    response.success = false;
    response.nodes = 0;
    response.message = e.what();
    ROS_WARN_STREAM("shell_sim: force refused: " << response.message);
  }
  return true;
}

bool ShellSimulator::saveCallback(relaxed_connectivity::SaveState::Request& request,
                                  relaxed_connectivity::SaveState::Response& response) {
  std::lock_guard<std::mutex> lock(loop_.mutex());
  try {
    const std::filesystem::path path(request.path);
    const std::string ext = path.extension().string();
    if (ext != ".ply" && ext != ".pcd" && ext != ".xyz")
      throw std::invalid_argument(request.path + ": unknown extension '" + ext +
                                  "' for shell surfels (supported: .ply .pcd .xyz)");
    writeCloud(request.path, simulation_->surfels());
    response.message = "saved " + std::to_string(simulation_->surfels().size()) + " surfels at frame " +
                       std::to_string(simulation_->frame()) + " to " + request.path;
    if (!simulation_->crackSurfels().empty()) {
      const std::string cracks = (path.parent_path() / (path.stem().string() + "_cracks" + ext)).string();
      writeCloud(cracks, simulation_->crackSurfels());
      response.message +=
          " and " + std::to_string(simulation_->crackSurfels().size()) + " crack surfels to " + cracks;
    }
    response.success = true;
  } catch (const std::exception& e) {
    response.success = false;
    response.message = e.what();
    ROS_WARN_STREAM("shell_sim: save failed: " << response.message);
  }
  return true;
}

bool ShellSimulator::holdCallback(relaxed_connectivity::ShellHold::Request& request,
                                  relaxed_connectivity::ShellHold::Response& response) {
  std::lock_guard<std::mutex> lock(loop_.mutex());
  response.success = false;
  response.nodes = 0;
  try {
    const Vec3 lo(request.lo.x, request.lo.y, request.lo.z), hi(request.hi.x, request.hi.y, request.hi.z);
    if (!lo.allFinite() || !hi.allFinite() || !(lo.array() <= hi.array()).all())
      throw std::invalid_argument("hold: the box needs finite lo <= hi");
    uint8_t mask = request.components.empty() ? 7 : 0;
    for (char k : request.components) {
      if (k < 'x' || k > 'z' || (mask >> (k - 'x') & 1))
        throw std::invalid_argument("hold: components '" + request.components +
                                    "' (letters of xyz, each once; empty: all)");
      mask |= uint8_t(1 << (k - 'x'));
    }
    const std::vector<uint32_t> nodes =
        shellNodesInBox(simulation_->solver().nodes(), lo, hi, "hold: the box");  // throws when empty
    for (uint32_t i : nodes) simulation_->mutableSolver().hold(i, mask);
    response.nodes = uint32_t(nodes.size());
    response.success = true;
    response.message = "holding " + std::string(request.components.empty() ? "xyz" : request.components) +
                       " of " + std::to_string(nodes.size()) + " nodes";
  } catch (const std::exception& e) {
    response.message = e.what();
    ROS_WARN_STREAM("shell_sim: hold refused: " << response.message);
  }
  return true;
}

}  // namespace rc
