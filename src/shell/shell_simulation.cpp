#include "relaxed_connectivity/shell/shell_simulation.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <chrono>
#include <cmath>

#include "relaxed_connectivity/shell/shell_scene_regions.h"

namespace rc {

namespace {

using Clock = std::chrono::steady_clock;
double msSince(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

}  // namespace

ShellSimulation::ShellSimulation(const ShellScene& scene) : scene_(scene) {
  solver_ = std::make_unique<ShellSolver>(selectShellNodes(scene_.surfels, scene_.nodes), scene_.material,
                                          scene_.solver);
  const ShellNodes& nodes = solver_->nodes();
  for (const ShellScenePin& pin : scene_.pins) {
    for (size_t i = 0; i < nodes.size(); ++i) {
      const Vec3& p = nodes.rest_positions[i];
      if ((p.array() < pin.lo.array()).any() || (p.array() > pin.hi.array()).any() || solver_->pinned(i))
        continue;
      if (pin.velocity.squaredNorm() > 0) {
        solver_->setPinVelocity(i, pin.velocity);  // moved in the solver's drift: one force pass per step
      } else {
        solver_->pin(i);
      }
    }
  }
  // Dynamic runs: held components of the held regions, constant loads (static and modal analyses use them in
  // shell_scene_analysis).
  std::vector<Vec3> loads;
  if (scene_.analysis == ShellAnalysis::kDynamic) {
    for (const ShellHeld& region : resolveShellHeld(scene_, nodes)) {
      const uint8_t mask =
          uint8_t(region.components[0] | region.components[1] << 1 | region.components[2] << 2);
      for (uint32_t i : region.nodes) solver_->hold(i, mask);
    }
    if (!scene_.loads.empty())
      loads = shellLoadForces(solver_->energy(), resolveShellLoads(scene_, nodes), Vec3::Zero());
  }
  if (scene_.initial_velocity.squaredNorm() > 0)
    solver_->setVelocities(std::vector<Vec3>(nodes.size(), scene_.initial_velocity));
  FiberStiffnessField field;
  if (scene_.anisotropy.enabled) {
    const ShellSceneAnisotropy a = scene_.anisotropy;
    field = [a](const Vec3&, const Vec3& direction) {
      const double c2 = std::pow(direction.dot(a.direction), 2);
      return std::make_pair(1.0 + (a.stretch_ratio - 1.0) * c2, 1.0 + (a.bend_ratio - 1.0) * c2);
    };
    setFiberStiffness(nodes, solver_->mutableFibers(), field);
    solver_->refreshForces();
  }
  if (scene_.balance_membrane) {
    membrane_balance_ = balanceMembraneStiffness(nodes, solver_->mutableFibers());
    solver_->refreshForces();
  }
  if (scene_.plasticity || scene_.fracture) {
    model_ = std::make_unique<ShellMaterialModel>(nodes, solver_->fibers(), scene_.material_options);
    if (field) model_->setStiffnessField(field);
    // Grips reinforce the material: fibers touching a pinned node do not fracture (the clamp corners would
    // otherwise tear first, a singularity of the displacement boundary condition).
    const ShellFibers& all = solver_->fibers();
    for (size_t q = 0; q < all.size(); ++q) {
      const Fiber& f = all.fibers[q];
      if (solver_->pinned(f.center) || solver_->pinned(f.end1) || solver_->pinned(f.end2)) {
        model_->states()[q].stretch_threshold = INFINITY;
        model_->states()[q].bend_threshold = INFINITY;
      }
    }
    const ShellSceneWeakPoint& w = scene_.weak_point;
    if (w.enabled) {
      const ShellFibers& fibers = solver_->fibers();
      for (size_t q = 0; q < fibers.size(); ++q) {
        if ((nodes.rest_positions[fibers.fibers[q].center] - w.center).norm() > w.radius) continue;
        FiberMaterialState& s = model_->states()[q];
        if (w.stretch_threshold > 0) s.stretch_threshold = std::min(s.stretch_threshold, w.stretch_threshold);
        if (w.bend_threshold > 0) s.bend_threshold = std::min(s.bend_threshold, w.bend_threshold);
      }
    }
  }
  if (scene_.balloon.enabled) {
    pressure_ = std::make_shared<double>(scene_.balloon.pressureAt(0.0));
    ShellExternalForce unit = balloonPressure(solver_->nodes(), solver_->fibers(), 1.0);
    std::shared_ptr<double> p = pressure_;
    solver_->setExternalForce([unit, p, loads](const std::vector<Vec3>& x, std::vector<Vec3>& force) {
      unit(x, force);
      for (Vec3& f : force) f *= *p;
      for (size_t i = 0; i < loads.size(); ++i) force[i] += loads[i];
    });
  } else if (!loads.empty()) {
    solver_->setExternalForce([loads](const std::vector<Vec3>&, std::vector<Vec3>& force) { force = loads; });
  }
  surfels_ = scene_.surfels;
  animateSurface();
}

void ShellSimulation::takeStep(ShellFrameReport* report) {
  if (pressure_) {
    const double tear_time = crackCount() > 0 ? model_->cracks().front().time : -1.0;  // the first crack
    *pressure_ = scene_.balloon.pressureAt(solver_->time(), tear_time);
  }
  Clock::time_point t0 = Clock::now();
  const ShellStepReport r = solver_->step();
  report->forces_ms += msSince(t0);
  report->dt = r.dt;
  if (model_) {
    t0 = Clock::now();
    model_->update(*solver_, r.dt);
    report->material_ms += msSince(t0);
  }
  ++report->frame_steps;
}

ShellFrameReport ShellSimulation::advanceFrame() {
  ShellFrameReport report;
  ++frame_;
  report.frame = frame_;
  report.frame_count = scene_.frame_count;
  if (scene_.steps_per_frame > 0) {
    for (int s = 0; s < scene_.steps_per_frame; ++s) takeStep(&report);
  } else {
    const double end = frame_ * scene_.frame_time;
    while (solver_->time() < end - 1e-9 * scene_.frame_time) takeStep(&report);
  }
  finishReport(&report);
  return report;
}

ShellFrameReport ShellSimulation::advanceSteps(int steps) {
  ShellFrameReport report;
  report.frame = frame_;
  report.frame_count = scene_.frame_count;
  for (int s = 0; s < steps; ++s) takeStep(&report);
  finishReport(&report);
  return report;
}

void ShellSimulation::finishReport(ShellFrameReport* report) {
  report->surface_ms = animateSurface();
  report->time = solver_->time();
  report->steps = solver_->stepCount();
  report->cracks = crackCount();
  report->pressure = pressure_ ? *pressure_ : 0.0;
}

double ShellSimulation::animateSurface() {
  const Clock::time_point t0 = Clock::now();
  const std::vector<ShellCrack> no_cracks;
  const std::vector<ShellCrack>& cracks = model_ ? model_->cracks() : no_cracks;
  ShellSkinningOptions options;
  options.node_count = scene_.skinning_nodes;
  if (!skinning_) {
    skinning_ = std::make_unique<ShellSkinning>(scene_.surfels, solver_->nodes(), cracks, options);
  } else if (cracks.size() != bound_cracks_) {
    // Only surfels that a new crack cuts from one of their nodes are re-bound (equal to a full re-binding);
    // one left with no visible node keeps its previous binding.
    if (skinning_->rebind(scene_.surfels, solver_->nodes(), cracks) > 0) ++skinning_fallbacks_;
  }
  if (cracks.size() != bound_cracks_ && !cracks.empty()) {
    // Each surfel of a pair is moved a little into its own piece (opposite its normal) so its nearest
    // nodes include visible ones also where the disc reaches past the shell's border.
    cracks_ = crackDiscontinuitySurfels(cracks);
    for (size_t k = 0; k < cracks_.size(); ++k)
      cracks_.positions[k] -= kCrackSurfelInset * cracks[k / 2].radius * cracks_.normals[k];
    try {
      if (crack_skinning_ && crack_skinning_->boundCracks() == crack_skinning_->size() / 2) {
        crack_skinning_->rebind(cracks_, solver_->nodes(), cracks);  // the pairs of earlier cracks stay
      } else {
        crack_skinning_ = std::make_unique<ShellSkinning>(cracks_, solver_->nodes(), cracks, options);
      }
    } catch (const std::invalid_argument&) {
      crack_skinning_.reset();
      cracks_.clear();  // a surfel with no visible node: no crack surfels until the next crack
    } catch (const std::runtime_error&) {
      crack_skinning_.reset();
      cracks_.clear();
    }
  }
  bound_cracks_ = cracks.size();
  skinning_->deform(solver_->nodes(), solver_->positions(), &surfels_);
  if (crack_skinning_) crack_skinning_->deform(solver_->nodes(), solver_->positions(), &cracks_);
  return msSince(t0);
}

double ShellSimulation::meanRadius() const {
  const std::vector<Vec3>& x = solver_->positions();
  Vec3 c = Vec3::Zero();
  for (const Vec3& p : x) c += p / double(x.size());
  double r = 0.0;
  for (const Vec3& p : x) r += (p - c).norm() / double(x.size());
  return r;
}

double ShellSimulation::maxCoordinate() const {
  double m = 0.0;
  for (const Vec3& p : solver_->positions()) {
    if (!p.allFinite()) return INFINITY;
    m = std::max(m, p.cwiseAbs().maxCoeff());
  }
  return m;
}

double ShellSimulation::maxSpeed() const {
  double m = 0.0;
  for (const Vec3& v : solver_->velocities()) {
    if (!v.allFinite()) return INFINITY;
    m = std::max(m, v.norm());
  }
  return m;
}

}  // namespace rc
