#include "relaxed_connectivity/ros/fem_simulator.h"

#include <relaxed_connectivity/FemProbes.h>
#include <relaxed_connectivity/FemStats.h>
#include <tf2_eigen/tf2_eigen.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>

#include "relaxed_connectivity/fem/fem_probes.h"
#include "relaxed_connectivity/fem/fem_scene_reader.h"
#include "relaxed_connectivity/ros/point_cloud2_converter.h"
#include "relaxed_connectivity/ros/simulation_loop.h"

namespace rc {

void FemSimulatorParams::validate() const {
  auto fail = [](const std::string& what) { throw std::invalid_argument("fem_sim: " + what); };
  if (scene.empty()) fail("parameter ~scene (an FEM scene file, config/fem/*.yaml) is required");
  if (frame_id.empty() || frame_id[0] == '/')
    fail("frame_id '" + frame_id + "' must be non-empty without '/'");
  if (!(rate > 0) || !std::isfinite(rate)) fail("rate must be > 0 Hz (got " + std::to_string(rate) + ")");
  if (!(real_time_factor > 0) || !std::isfinite(real_time_factor))
    fail("real_time_factor must be > 0 (got " + std::to_string(real_time_factor) + ")");
  if (!(tf_timeout >= 0) || !std::isfinite(tf_timeout))
    fail("tf_timeout must be >= 0 s (got " + std::to_string(tf_timeout) + ")");
  if (!(planarity_tolerance > 0) || !(planarity_tolerance < 1))
    fail("planarity_tolerance must be in (0, 1) (got " + std::to_string(planarity_tolerance) + ")");
}

FemSimulatorParams readFemSimulatorParams(const ros::NodeHandle& pnh) {
  FemSimulatorParams p;
  pnh.param("scene", p.scene, p.scene);
  pnh.param("frame_id", p.frame_id, p.frame_id);
  pnh.param("rate", p.rate, p.rate);
  pnh.param("autostart", p.autostart, p.autostart);
  pnh.param("real_time_factor", p.real_time_factor, p.real_time_factor);
  pnh.param("tf_timeout", p.tf_timeout, p.tf_timeout);
  pnh.param("planarity_tolerance", p.planarity_tolerance, p.planarity_tolerance);
  p.validate();
  return p;
}

visualization_msgs::Marker femSurfaceMarker(const std::vector<FemBodyState>& bodies) {
  static const std::array<std::array<float, 3>, 6> kPalette = {{{0.85f, 0.55f, 0.25f},
                                                                {0.30f, 0.60f, 0.90f},
                                                                {0.45f, 0.80f, 0.35f},
                                                                {0.85f, 0.35f, 0.55f},
                                                                {0.65f, 0.50f, 0.90f},
                                                                {0.90f, 0.80f, 0.30f}}};
  visualization_msgs::Marker marker;
  marker.type = visualization_msgs::Marker::TRIANGLE_LIST;
  marker.action = visualization_msgs::Marker::ADD;
  marker.pose.orientation.w = 1.0;
  marker.scale.x = marker.scale.y = marker.scale.z = 1.0;
  marker.color.r = marker.color.g = marker.color.b = marker.color.a = 1.0f;
  size_t triangles = 0;
  for (const FemBodyState& body : bodies) triangles += body.mesh->boundaryTriangles().size();
  marker.points.reserve(3 * triangles);
  marker.colors.reserve(3 * triangles);
  for (size_t b = 0; b < bodies.size(); ++b) {
    std_msgs::ColorRGBA color;
    color.r = kPalette[b % kPalette.size()][0];
    color.g = kPalette[b % kPalette.size()][1];
    color.b = kPalette[b % kPalette.size()][2];
    color.a = 1.0f;
    const Eigen::VectorXd& x = *bodies[b].positions;
    for (const PolyhedralMesh::Triangle& triangle : bodies[b].mesh->boundaryTriangles())
      for (int v : triangle) {
        geometry_msgs::Point point;
        point.x = x[3 * v];
        point.y = x[3 * v + 1];
        point.z = x[3 * v + 2];
        marker.points.push_back(point);
        marker.colors.push_back(color);
      }
  }
  return marker;
}

FemSimulator::FemSimulator(ros::NodeHandle nh, ros::NodeHandle private_nh)
    : nh_(nh),
      private_nh_(private_nh),
      params_(readFemSimulatorParams(private_nh)),
      tf_listener_(tf_buffer_, nh),
      loop_("fem_sim", loopCallbacks()) {
  surface_pub_ = private_nh_.advertise<visualization_msgs::Marker>("surface", 1);
  nodes_pub_ = private_nh_.advertise<sensor_msgs::PointCloud2>("nodes", 1);
  stats_pub_ = private_nh_.advertise<relaxed_connectivity::FemStats>("stats", 1);
  probes_pub_ = private_nh_.advertise<relaxed_connectivity::FemProbes>("probes", 10);
  scene_ = std::make_unique<FemScene>(loadFemScene(params_.scene));
  probe_tolerance_ = femBoxTolerance(*scene_->mesh);
  simulation_ = std::make_unique<FemSimulation>(*scene_);
  loop_.setRunning(params_.autostart);
  ROS_INFO_STREAM("fem_sim: loaded " << params_.scene << ": " << simulation_->numElements() << " elements, "
                                     << simulation_->numNodes() << " nodes, " << scene_->cuts.size()
                                     << " scheduled cuts");
  cut_srv_ = private_nh_.advertiseService("cut", &FemSimulator::cutCallback, this);
  load_srv_ = private_nh_.advertiseService("load", &FemSimulator::loadCallback, this);
  hold_srv_ = private_nh_.advertiseService("hold", &FemSimulator::holdCallback, this);
  save_srv_ = private_nh_.advertiseService("save", &FemSimulator::saveCallback, this);
  loop_.start(nh_, private_nh_, params_.rate);
}

SimulationLoopCallbacks FemSimulator::loopCallbacks() {
  SimulationLoopCallbacks c;
  c.tick = [this] {
    return advance(params_.real_time_factor / params_.rate, std::numeric_limits<uint64_t>::max());
  };
  c.step = [this](uint32_t steps) { return advance(std::numeric_limits<double>::infinity(), steps); };
  c.frame = [this](uint32_t frames) {
    return advance(std::numeric_limits<double>::infinity(),
                   uint64_t(frames) * uint64_t(scene_->steps_per_frame));
  };
  c.where = [this] {
    return "step " + std::to_string(simulation_->steps()) + ", t = " + std::to_string(simulation_->time()) +
           " s";
  };
  c.reset = [this] {
    resetSimulation();
    return "reset to t = 0: " + std::to_string(simulation_->numElements()) + " elements, " +
           std::to_string(simulation_->numNodes()) + " nodes";
  };
  c.publish = [this] { publish(); };
  c.time = [this] { return simulation_->time(); };
  return c;
}

void FemSimulator::resetSimulation() {
  simulation_ = std::make_unique<FemSimulation>(*scene_);
  loop_.setRunning(false);
  loop_.setError("");
  interactive_cuts_ = 0;
  step_ms_ = 0.0;
}

std::string FemSimulator::advance(double duration, uint64_t steps) {
  const double end = simulation_->time() + duration;
  uint64_t done = 0;
  const auto start = std::chrono::steady_clock::now();
  while (done < steps && simulation_->time() < end) {
    try {
      simulation_->step();
    } catch (const std::exception& e) {
      // A failing scheduled cut may have replaced some bodies, a failing step left a non-finite state: back
      // to the scene's start, paused, with the reason in the stats.
      const std::string what = e.what();
      resetSimulation();
      return what + " (reset to t = 0, paused)";
    }
    ++done;
  }
  if (done > 0)
    step_ms_ =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count() / done;
  return std::string();
}

void FemSimulator::publish() {
  std::lock_guard<std::mutex> lock(loop_.mutex());
  const ros::Time stamp = loop_.stamp();
  const std::vector<FemBodyState> bodies = simulation_->bodyStates();
  size_t triangles = 0;
  for (const FemBodyState& body : bodies) triangles += body.mesh->boundaryTriangles().size();
  if (nodes_pub_.getNumSubscribers() > 0) {
    SurfelCloud cloud = femNodesToCloud(bodies);
    cloud.frame_id = params_.frame_id;
    cloud.stamp_ns = stamp.toNSec();
    nodes_pub_.publish(PointCloud2Converter::toMessage(cloud, PointCloud2Layout::kCompact));
  }
  if (surface_pub_.getNumSubscribers() > 0) {
    visualization_msgs::Marker marker = femSurfaceMarker(bodies);
    marker.header.frame_id = params_.frame_id;
    marker.header.stamp = stamp;
    marker.ns = "fem_surface";
    surface_pub_.publish(marker);
  }
  relaxed_connectivity::FemStats stats;
  stats.header.frame_id = params_.frame_id;
  stats.header.stamp = stamp;
  stats.scene = scene_->name;
  stats.running = loop_.running();
  stats.step = uint64_t(simulation_->steps());
  stats.time = simulation_->time();
  stats.dt = scene_->dynamics.time_step;
  stats.bodies = uint32_t(simulation_->numBodies());
  stats.nodes = uint32_t(simulation_->numNodes());
  stats.elements = uint32_t(simulation_->numElements());
  stats.surface_triangles = uint32_t(triangles);
  stats.scheduled_cuts = uint32_t(simulation_->cutsApplied());
  stats.interactive_cuts = uint32_t(interactive_cuts_);
  stats.max_step_iterations = uint32_t(simulation_->maxStepIterations());
  stats.unconverged_solves = uint64_t(simulation_->unconvergedSolves());
  stats.min_ground_distance = simulation_->minGroundDistance();
  stats.step_ms = step_ms_;
  stats.topology_ms = 1e3 * simulation_->phaseTimes().topology;
  stats.error = loop_.error();
  stats_pub_.publish(stats);
  if (!scene_->probes.empty()) publishProbes(stats.header);
}

void FemSimulator::publishProbes(const std_msgs::Header& header) {
  // The scene's probes (its key probes), as rc_fem writes them per frame.
  std::vector<const WarpedDynamics*> bodies;
  for (int b = 0; b < simulation_->numBodies(); ++b) bodies.push_back(&simulation_->body(b));
  const FemBodiesMeasures all = measureFemBodies(bodies);
  relaxed_connectivity::FemProbes probes;
  probes.header = header;
  probes.scene = scene_->name;
  probes.time = simulation_->time();
  probes.kinetic_energy = all.kinetic_energy;
  probes.elastic_energy = all.elastic_energy;
  probes.gravity_potential_energy = all.gravity_potential_energy;
  probes.momentum.x = all.momentum.x(), probes.momentum.y = all.momentum.y(),
  probes.momentum.z = all.momentum.z();
  for (const FemProbe& probe : scene_->probes) {
    const FemRegionMeasures m = measureFemRegion(bodies, probe, probe_tolerance_);
    probes.names.push_back(probe.name);
    probes.nodes.push_back(uint32_t(m.nodes));
    probes.masses.push_back(m.mass);
    geometry_msgs::Vector3 u;
    u.x = m.mean_displacement.x(), u.y = m.mean_displacement.y(), u.z = m.mean_displacement.z();
    probes.mean_displacements.push_back(u);
    probes.max_displacements.push_back(m.max_displacement);
    geometry_msgs::Vector3 r;
    r.x = m.reaction.x(), r.y = m.reaction.y(), r.z = m.reaction.z();
    probes.reactions.push_back(r);
  }
  probes_pub_.publish(probes);
}

std::vector<Vec3> FemSimulator::polygonInSceneFrame(const relaxed_connectivity::FemCut::Request& request) {
  const std::string& frame = request.header.frame_id;
  if (frame.empty())
    throw std::invalid_argument("header.frame_id is empty (give the polygon's frame, e.g. '" +
                                params_.frame_id + "')");
  Eigen::Isometry3d to_scene = Eigen::Isometry3d::Identity();
  if (frame != params_.frame_id) {
    try {
      to_scene = tf2::transformToEigen(tf_buffer_.lookupTransform(
          params_.frame_id, frame, request.header.stamp, ros::Duration(params_.tf_timeout)));
    } catch (const tf2::TransformException& e) {
      throw std::runtime_error("no transform from '" + frame + "' to '" + params_.frame_id +
                               "': " + e.what());
    }
  }
  std::vector<Vec3> polygon;
  polygon.reserve(request.polygon.size());
  for (const geometry_msgs::Point& p : request.polygon) polygon.push_back(to_scene * Vec3(p.x, p.y, p.z));
  return polygon;
}

bool FemSimulator::loadCallback(relaxed_connectivity::FemLoad::Request& request,
                                relaxed_connectivity::FemLoad::Response& response) {
  std::lock_guard<std::mutex> lock(loop_.mutex());
  response.success = false;
  response.nodes = 0;
  try {
    FemLoad load;
    load.lo = Vec3(request.lo.x, request.lo.y, request.lo.z);
    load.hi = Vec3(request.hi.x, request.hi.y, request.hi.z);
    load.force = Vec3(request.force.x, request.force.y, request.force.z);
    load.is_traction = request.traction;
    if (!load.lo.allFinite() || !load.hi.allFinite() || !load.force.allFinite() ||
        !(load.lo.array() <= load.hi.array()).all())
      throw std::invalid_argument("load: needs a finite box with lo <= hi and a finite force");
    std::vector<FemLoad> loads = request.clear ? std::vector<FemLoad>() : simulation_->scene().loads;
    const bool adds = !(request.clear && load.force.isZero());
    if (adds) loads.push_back(load);
    const std::vector<FemLoad> before = simulation_->scene().loads;
    const std::vector<size_t> counts = simulation_->setLoads(loads);
    if (adds && counts.back() == 0) {
      simulation_->setLoads(before);  // changes nothing
      throw std::invalid_argument("load: the box holds no node of the bodies' rest positions");
    }
    response.nodes = adds ? uint32_t(counts.back()) : 0;
    response.loads = uint32_t(loads.size());
    response.success = true;
    response.message = adds ? "force spread over " + std::to_string(response.nodes) + " nodes; " +
                                  std::to_string(loads.size()) + " loads"
                            : "loads cleared";
  } catch (const std::exception& e) {
    response.message = e.what();
    ROS_WARN_STREAM("fem_sim: load refused: " << response.message);
  }
  return true;
}

bool FemSimulator::saveCallback(relaxed_connectivity::SaveState::Request& request,
                                relaxed_connectivity::SaveState::Response& response) {
  std::lock_guard<std::mutex> lock(loop_.mutex());
  try {
    writeFemState(request.path, simulation_->bodyStates());
    response.success = true;
    response.message = "saved " + std::to_string(simulation_->numBodies()) +
                       " bodies at t = " + std::to_string(simulation_->time()) + " s to " + request.path;
  } catch (const std::exception& e) {
    response.success = false;
    response.message = e.what();
    ROS_WARN_STREAM("fem_sim: save failed: " << response.message);
  }
  return true;
}

bool FemSimulator::holdCallback(relaxed_connectivity::FemHold::Request& request,
                                relaxed_connectivity::FemHold::Response& response) {
  std::lock_guard<std::mutex> lock(loop_.mutex());
  response.success = false;
  response.nodes = 0;
  try {
    FemHeldRegion region;
    region.lo = Vec3(request.lo.x, request.lo.y, request.lo.z);
    region.hi = Vec3(request.hi.x, request.hi.y, request.hi.z);
    region.displacement = Vec3(request.displacement.x, request.displacement.y, request.displacement.z);
    region.in_place = request.in_place;
    if (!region.lo.allFinite() || !region.hi.allFinite() || !(region.lo.array() <= region.hi.array()).all())
      throw std::invalid_argument("hold: needs a finite box with lo <= hi");
    if (!request.components.empty()) {
      region.components = {false, false, false};
      for (char k : request.components) {
        if (k < 'x' || k > 'z')
          throw std::invalid_argument("hold: components '" + request.components + "' are not letters of xyz");
        region.components[size_t(k - 'x')] = true;
      }
    }
    if (request.path_times.size() != request.path_displacements.size())
      throw std::invalid_argument("hold: " + std::to_string(request.path_times.size()) + " path times for " +
                                  std::to_string(request.path_displacements.size()) + " displacements");
    for (size_t k = 0; k < request.path_times.size(); ++k) {
      const geometry_msgs::Vector3& u = request.path_displacements[k];
      region.path.emplace_back(simulation_->time() + request.path_times[k], Vec3(u.x, u.y, u.z));
    }
    const bool adds = !(request.clear && region.lo.isZero() && region.hi.isZero());
    std::vector<FemHeldRegion> regions =
        request.clear ? std::vector<FemHeldRegion>() : simulation_->scene().held;
    if (adds) regions.push_back(region);
    const std::vector<FemHeldRegion> before = simulation_->scene().held;
    const std::vector<size_t> counts = simulation_->setHeld(regions);  // throws before changing anything
    if (adds && counts.back() == 0) {
      simulation_->setHeld(before);  // changes nothing
      throw std::invalid_argument("hold: the box holds no node of the bodies' rest positions");
    }
    response.nodes = adds ? uint32_t(counts.back()) : 0;
    response.regions = uint32_t(regions.size());
    response.success = true;
    response.message = adds ? "holding " + std::to_string(response.nodes) + " nodes; " +
                                  std::to_string(regions.size()) + " held regions"
                            : "held regions released";
  } catch (const std::exception& e) {
    response.message = e.what();
    ROS_WARN_STREAM("fem_sim: hold refused: " << response.message);
  }
  return true;
}

bool FemSimulator::cutCallback(relaxed_connectivity::FemCut::Request& request,
                               relaxed_connectivity::FemCut::Response& response) {
  response.success = false;
  FemSceneCut cut;
  try {
    cut = femCutFromPolygon(polygonInSceneFrame(request), params_.planarity_tolerance);
    cut.separate = !request.keep_connected;
  } catch (const std::exception& e) {
    response.message = e.what();
    ROS_WARN_STREAM("fem_sim: cut refused: " << response.message);
    std::lock_guard<std::mutex> lock(loop_.mutex());
    response.bodies = uint32_t(simulation_->numBodies());
    response.nodes = uint32_t(simulation_->numNodes());
    response.elements = uint32_t(simulation_->numElements());
    return true;
  }
  {
    std::lock_guard<std::mutex> lock(loop_.mutex());
    {
      const auto start = std::chrono::steady_clock::now();
      try {
        const FemCutReport report =
            request.progressive ? simulation_->applyPolygonCuts({cut.region}, cut.snap_relative_distance)
                                : simulation_->applyCut(cut);
        response.success = true;
        response.bodies_cut = uint32_t(report.bodies_cut);
        response.bodies_separated = uint32_t(report.bodies_separated);
        response.split_elements = uint32_t(report.split_elements);
        response.new_nodes = uint32_t(report.new_nodes);
        response.duplicated_nodes = uint32_t(report.duplicated_nodes);
        response.crack_faces = uint32_t(report.crack_faces);
        if (report.bodies_cut > 0) ++interactive_cuts_;
        const double ms =
            std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
        response.message =
            report.bodies_cut == 0
                ? std::string("the polygon crosses no element: nothing changed")
                : "split " + std::to_string(report.split_elements) + " elements, " +
                      std::to_string(report.new_nodes) + " new nodes, " +
                      (request.progressive ? std::to_string(report.crack_faces) + " crack faces, "
                                           : std::string()) +
                      std::to_string(report.bodies_separated) + " bodies separated (" + std::to_string(ms) +
                      " ms)";
      } catch (const std::exception& e) {
        // applyCut may have replaced some bodies before it failed: back to the scene's start.
        resetSimulation();
        response.message = std::string("cut failed: ") + e.what() + "; the simulation was reset to t = 0";
      }
    }
    response.bodies = uint32_t(simulation_->numBodies());
    response.nodes = uint32_t(simulation_->numNodes());
    response.elements = uint32_t(simulation_->numElements());
    ROS_INFO_STREAM("fem_sim: cut: " << response.message);
  }
  publish();
  return true;
}

}  // namespace rc
