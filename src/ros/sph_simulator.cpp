#include "relaxed_connectivity/ros/sph_simulator.h"

#include <relaxed_connectivity/SphProbes.h>
#include <relaxed_connectivity/SphStats.h>
#include <visualization_msgs/Marker.h>

#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <vector>

#include "relaxed_connectivity/ros/point_cloud2_converter.h"
#include "relaxed_connectivity/ros/simulation_loop.h"
#include "relaxed_connectivity/sph/sph_output.h"
#include "relaxed_connectivity/sph/sph_probes.h"
#include "relaxed_connectivity/sph/sph_scene_reader.h"
#include "relaxed_connectivity/sph/sph_simulation.h"
#include "relaxed_connectivity/sph/sph_surface.h"

namespace rc {

void SphSimulatorParams::validate() const {
  auto fail = [](const std::string& what) { throw std::invalid_argument("sph_sim: " + what); };
  if (frame_id.empty() || frame_id[0] == '/')
    fail("frame_id '" + frame_id + "' must be non-empty without '/'");
  if (!(rate > 0) || !std::isfinite(rate)) fail("rate must be > 0 Hz (got " + std::to_string(rate) + ")");
  if (!(real_time_factor > 0) || !std::isfinite(real_time_factor))
    fail("real_time_factor must be > 0 (got " + std::to_string(real_time_factor) + ")");
  if (!(surface_cell_size >= 0) || !std::isfinite(surface_cell_size))
    fail("surface_cell_size must be >= 0 (got " + std::to_string(surface_cell_size) + ")");
  if (threads < 0) fail("threads must be >= 0");
}

SphSimulatorParams readSphSimulatorParams(const ros::NodeHandle& pnh) {
  SphSimulatorParams p;
  pnh.param("scene", p.scene, p.scene);
  pnh.param("frame_id", p.frame_id, p.frame_id);
  pnh.param("rate", p.rate, p.rate);
  pnh.param("autostart", p.autostart, p.autostart);
  pnh.param("real_time_factor", p.real_time_factor, p.real_time_factor);
  pnh.param("surface", p.surface, p.surface);
  pnh.param("surface_cell_size", p.surface_cell_size, p.surface_cell_size);
  pnh.param("threads", p.threads, p.threads);
  p.validate();
  return p;
}

SphSimulator::SphSimulator(ros::NodeHandle nh, ros::NodeHandle private_nh)
    : nh_(nh),
      private_nh_(private_nh),
      params_(readSphSimulatorParams(private_nh)),
      loop_("sph_sim", loopCallbacks()) {
  particles_pub_ = private_nh_.advertise<sensor_msgs::PointCloud2>("particles", 1);
  surface_pub_ = private_nh_.advertise<visualization_msgs::Marker>("surface", 1);
  stats_pub_ = private_nh_.advertise<relaxed_connectivity::SphStats>("stats", 1);
  probes_pub_ = private_nh_.advertise<relaxed_connectivity::SphProbes>("probes", 10);
  if (!params_.scene.empty()) {
    std::string message;
    if (!load(params_.scene, params_.autostart, &message)) throw std::invalid_argument(message);
  }
  load_srv_ = private_nh_.advertiseService("load_scene", &SphSimulator::loadCallback, this);
  save_srv_ = private_nh_.advertiseService("save", &SphSimulator::saveCallback, this);
  loop_.start(nh_, private_nh_, params_.rate);
}

SimulationLoopCallbacks SphSimulator::loopCallbacks() {
  SimulationLoopCallbacks c;
  c.ready = [this] { return simulation_ != nullptr; };
  c.not_ready_message = "no scene loaded (call ~load_scene)";
  c.tick = [this] {
    return advance(params_.real_time_factor / params_.rate, std::numeric_limits<uint64_t>::max());
  };
  c.step = [this](uint32_t steps) { return advance(std::numeric_limits<double>::infinity(), steps); };
  c.frame = [this](uint32_t frames) {  // until the frames' simulated time has passed
    return advance(frames * scene_->frame_time, std::numeric_limits<uint64_t>::max());
  };
  c.where = [this] {
    return "step " + std::to_string(simulation_->solver().stepCount()) +
           ", t = " + std::to_string(simulation_->solver().time()) + " s";
  };
  c.reset = [this] {
    simulation_ = std::make_unique<SphSimulation>(*scene_);
    simulation_->emit(simulation_->solver().time());
    return std::string("reset to t = 0");
  };
  c.publish = [this] { publish(); };
  c.time = [this] { return simulation_->solver().time(); };
  c.error_needs_reset = true;  // the unstable state stays for inspection
  return c;
}

bool SphSimulator::load(const std::string& path, bool start, std::string* message) {
  try {
    auto scene = std::make_unique<SphScene>(loadSphScene(path));
    if (params_.threads > 0) scene->config.num_threads = params_.threads;
    scene->config.throw_on_instability = false;  // reported in the stats, the simulation pauses
    auto simulation = std::make_unique<SphSimulation>(*scene);
    simulation->emit(simulation->solver().time());  // the sources' first layers
    std::lock_guard<std::mutex> lock(loop_.mutex());
    simulation_.reset();  // refers to the old scene
    scene_ = std::move(scene);
    simulation_ = std::move(simulation);
    loop_.setRunning(start);
    loop_.setError("");
    step_ms_ = 0.0;
    *message = "loaded " + path + ": " + std::to_string(scene_->particles.size()) + " particles";
    for (const std::string& warning : scene_->warnings) {
      ROS_WARN_STREAM("sph_sim: " << warning);
      *message += "; " + warning;
    }
    ROS_INFO_STREAM("sph_sim: " << *message);
  } catch (const std::exception& e) {
    *message = e.what();
    ROS_ERROR_STREAM("sph_sim: cannot load " << path << ": " << e.what());
    return false;
  }
  publish();
  return true;
}

std::string SphSimulator::advance(double duration, uint64_t steps) {
  const double end = simulation_->solver().time() + duration;
  uint64_t done = 0;
  const auto start = std::chrono::steady_clock::now();
  while (done < steps && simulation_->solver().time() < end) {
    const SphStepStats& stats = simulation_->step();  // with temperature, phase changes and sources
    ++done;
    if (stats.unstable) break;
  }
  if (done > 0)
    step_ms_ =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count() / done;
  const SphStepStats& last = simulation_->solver().lastStats();
  return done > 0 && last.unstable ? last.instability : std::string();
}

void SphSimulator::publish() {
  std::lock_guard<std::mutex> lock(loop_.mutex());
  if (!simulation_) return;
  const ros::Time stamp = loop_.stamp();
  const SphParticles& particles = simulation_->solver().particles();
  if (particles_pub_.getNumSubscribers() > 0) {
    const SphThermalModel* thermal = simulation_->thermal().get();
    SurfelCloud cloud = sphParticlesToCloud(particles, thermal ? &thermal->temperatures() : nullptr);
    cloud.frame_id = params_.frame_id;
    cloud.stamp_ns = stamp.toNSec();
    particles_pub_.publish(PointCloud2Converter::toMessage(cloud, PointCloud2Layout::kCompact));
  }
  if (params_.surface && surface_pub_.getNumSubscribers() > 0) {
    SphSurfaceConfig surface;
    surface.smoothing_length = simulation_->solver().config().smoothing_length;
    surface.cell_size = params_.surface_cell_size;
    surface.rest_density = simulation_->solver().config().rest_density;
    const TriangleMesh mesh = extractSphSurface(particles, surface);
    visualization_msgs::Marker marker;
    marker.header.frame_id = params_.frame_id;
    marker.header.stamp = stamp;
    marker.ns = "sph_surface";
    marker.type = visualization_msgs::Marker::TRIANGLE_LIST;
    marker.action = visualization_msgs::Marker::ADD;
    marker.pose.orientation.w = 1.0;
    marker.scale.x = marker.scale.y = marker.scale.z = 1.0;
    marker.color.r = 0.25f;
    marker.color.g = 0.5f;
    marker.color.b = 0.95f;
    marker.color.a = 0.8f;
    marker.points.reserve(mesh.triangles.size() * 3);
    for (const auto& triangle : mesh.triangles)
      for (int k = 0; k < 3; ++k) {
        geometry_msgs::Point point;
        const Vec3& vertex = mesh.vertices.positions[triangle[k]];
        point.x = vertex.x();
        point.y = vertex.y();
        point.z = vertex.z();
        marker.points.push_back(point);
      }
    surface_pub_.publish(marker);
  }
  relaxed_connectivity::SphStats stats;
  stats.header.frame_id = params_.frame_id;
  stats.header.stamp = stamp;
  stats.scene = scene_->name;
  stats.running = loop_.running();
  stats.step = simulation_->solver().stepCount();
  stats.time = simulation_->solver().time();
  const SphStepStats& last = simulation_->solver().lastStats();
  stats.dt = last.dt;
  stats.dt_limit = toString(last.limit);
  stats.particles = uint32_t(particles.size());
  stats.fluid_particles = uint32_t(particles.count(SphParticleKind::kFluid));
  stats.max_speed = last.max_speed;
  stats.max_density_error = last.max_density_error;
  stats.kinetic_energy = last.kinetic_energy;
  stats.step_ms = step_ms_;
  stats.melted = simulation_->melted();
  stats.frozen = simulation_->frozen();
  stats.instability = loop_.error();
  stats_pub_.publish(stats);
  if (scene_->probes.enabled) {  // the scene's probes (its key probes), as rc_sph writes them per frame
    const SphFluidConfig& config = simulation_->solver().config();
    const SphKernels kernels(config.dimension, config.smoothing_length);
    const SphBodyMeasures body = measureSphBody(particles);
    auto point = [](const Vec3& v) {
      geometry_msgs::Point p;
      p.x = v.x(), p.y = v.y(), p.z = v.z();
      return p;
    };
    relaxed_connectivity::SphProbes probes;
    probes.header = stats.header;
    probes.scene = scene_->name;
    probes.time = stats.time;
    probes.particles = uint32_t(body.particles);
    probes.mass = body.mass;
    probes.kinetic_energy = body.kinetic_energy;
    probes.momentum.x = body.momentum.x(), probes.momentum.y = body.momentum.y();
    probes.momentum.z = body.momentum.z();
    probes.centre = point(body.centre);
    probes.lo = point(body.lo);
    probes.hi = point(body.hi);
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) probes.second_moments[size_t(3 * r + c)] = body.second_moments(r, c);
    for (const Vec3& x : scene_->probes.points) {
      const SphPointSample sample = sampleSphPoint(particles, kernels, x);
      probes.points.push_back(point(x));
      probes.densities.push_back(sample.density);
      probes.pressures.push_back(sample.pressure);
    }
    probes_pub_.publish(probes);
  }
}

bool SphSimulator::saveCallback(relaxed_connectivity::SaveState::Request& request,
                                relaxed_connectivity::SaveState::Response& response) {
  std::lock_guard<std::mutex> lock(loop_.mutex());
  response.success = false;
  if (!simulation_) {
    response.message = "no scene loaded";
    return true;
  }
  try {
    const SphParticles& particles = simulation_->solver().particles();
    std::vector<double> temperatures;
    if (simulation_->thermal()) {
      temperatures = simulation_->thermal()->temperatures();
      temperatures.resize(particles.size(), simulation_->thermal()->config().initial_temperature);
    }
    writeSphState(request.path, particles, simulation_->thermal() ? &temperatures : nullptr);
    response.success = true;
    response.message = "saved " + std::to_string(particles.size()) +
                       " particles at t = " + std::to_string(simulation_->solver().time()) + " s to " +
                       request.path;
  } catch (const std::exception& e) {
    response.message = e.what();
    ROS_WARN_STREAM("sph_sim: save failed: " << response.message);
  }
  return true;
}

bool SphSimulator::loadCallback(relaxed_connectivity::LoadSphScene::Request& request,
                                relaxed_connectivity::LoadSphScene::Response& response) {
  response.success = load(request.path, request.start, &response.message);
  std::lock_guard<std::mutex> lock(loop_.mutex());
  response.particles = simulation_ ? uint32_t(simulation_->solver().particles().size()) : 0;
  return true;
}

}  // namespace rc
