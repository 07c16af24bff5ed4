#include "relaxed_connectivity/shell/shell_material.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <set>
#include <stdexcept>
#include <string>

namespace rc {
namespace {

constexpr size_t kParallelNodes = 2048;

Vec3 restDirection(const ShellNodes& nodes, const Fiber& f) {
  return (nodes.rest_positions[f.end2] - nodes.rest_positions[f.end1]).normalized();
}

void applyField(const ShellNodes& nodes, Fiber& f, const FiberStiffnessField& field) {
  const std::pair<double, double> s = field(nodes.rest_positions[f.center], restDirection(nodes, f));
  if (!(s.first >= 0.0) || !(s.second >= 0.0) || !std::isfinite(s.first) || !std::isfinite(s.second)) {
    throw std::invalid_argument("FiberStiffnessField: fiber at node " + std::to_string(f.center) +
                                " got a negative or non-finite stiffness factor");
  }
  f.stretch_scale = s.first;
  f.bend_scale = s.second;
}

// Current area ratio A_i / A_i^0 of node i from its fibers (7.5, 7.6); 1 without fibers.
double areaRatio(const ShellFibers& fibers, size_t i, const std::vector<Vec3>& x) {
  double s = 0.0, s0 = 0.0;
  for (size_t q = fibers.node_offsets[i]; q < fibers.node_offsets[i + 1]; ++q) {
    const Fiber& f = fibers.fibers[q];
    const double l = fiberArcLength(x[f.end1], x[i], x[f.end2]);
    s += f.weight * l * l;
    s0 += f.weight * f.rest_length * f.rest_length;
  }
  return s0 > 0.0 ? s / s0 : 1.0;
}

}  // namespace

void setFiberStiffness(const ShellNodes& nodes, ShellFibers& fibers, const FiberStiffnessField& field) {
  if (!field) throw std::invalid_argument("setFiberStiffness: empty stiffness field");
  for (Fiber& f : fibers.fibers) applyField(nodes, f, field);
}

void measureFibers(const ShellNodes& nodes, const ShellFibers& fibers, const std::vector<Vec3>& x,
                   std::vector<double>* length, std::vector<double>* angle) {
  const size_t n = nodes.size();
  if (x.size() != n) throw std::invalid_argument("measureFibers: position count differs from node count");
  length->resize(fibers.size());
  angle->resize(fibers.size());
#pragma omp parallel for schedule(static) if (n >= kParallelNodes)
  for (size_t i = 0; i < n; ++i) {
    const Vec3 normal = fanNormal(nodes, i, x);
    for (size_t q = fibers.node_offsets[i]; q < fibers.node_offsets[i + 1]; ++q) {
      const Fiber& f = fibers.fibers[q];
      (*length)[q] = fiberArcLength(x[f.end1], x[i], x[f.end2]);
      (*angle)[q] = fiberNormalAngle(x[f.end1], x[i], x[f.end2], normal);
    }
  }
}

ShellExternalForce balloonPressure(const ShellNodes& nodes, const ShellFibers& fibers, double pressure) {
  if (!std::isfinite(pressure)) throw std::invalid_argument("balloonPressure: pressure must be finite");
  const ShellNodes* np = &nodes;
  const ShellFibers* fp = &fibers;
  return [np, fp, pressure](const std::vector<Vec3>& x, std::vector<Vec3>& force) {
    const size_t n = np->size();
    force.resize(n);
#pragma omp parallel for schedule(static) if (n >= kParallelNodes)
    for (size_t i = 0; i < n; ++i) {
      force[i] = pressure * np->rest_areas[i] * areaRatio(*fp, i, x) * fanNormal(*np, i, x);
    }
  };
}

double balloonVolume(const ShellNodes& nodes, const ShellFibers& fibers, const std::vector<Vec3>& x) {
  double v = 0.0;
  for (size_t i = 0; i < nodes.size(); ++i) {
    v += nodes.rest_areas[i] * areaRatio(fibers, i, x) * fanNormal(nodes, i, x).dot(x[i]) / 3.0;
  }
  return v;
}

ShellMaterialModel::ShellMaterialModel(const ShellNodes& nodes, const ShellFibers& fibers,
                                       const ShellMaterialOptions& options)
    : options_(options) {
  const ShellPlasticity& p = options.plasticity;
  const ShellFracture& fr = options.fracture;
  if (!(p.stretch_yield >= 0.0) || !(p.bend_yield >= 0.0) || !(p.stretch_creep >= 0.0) ||
      !(p.bend_creep >= 0.0) || !(p.weakening >= 0.0) || !(fr.stretch_threshold > 0.0) ||
      !(fr.bend_threshold > 0.0) || fr.max_cracks_per_step < 1 || !(fr.min_fiber_length >= 0.0) ||
      !(fr.max_crack_speed > 0.0)) {
    throw std::invalid_argument(
        "ShellMaterialOptions: yields, creeps, weakening and min_fiber_length must be >= 0, fracture "
        "thresholds and max_crack_speed > 0, max_cracks_per_step >= 1");
  }
  if (fibers.node_offsets.size() != nodes.size() + 1) {
    throw std::invalid_argument("ShellMaterialModel: the fibers were built for another node set");
  }
  states_.resize(fibers.size());
  for (size_t q = 0; q < fibers.size(); ++q) {
    states_[q].original_length = fibers.fibers[q].rest_length;
    states_[q].original_angle = fibers.fibers[q].rest_angle;
    states_[q].stretch_threshold = fr.stretch_threshold;
    states_[q].bend_threshold = fr.bend_threshold;
  }
  neighbor_count_ = 3;
  for (size_t i = 0; i < nodes.size(); ++i)
    neighbor_count_ = std::max(neighbor_count_, nodes.neighborCount(i));
}

ShellMaterialReport ShellMaterialModel::updatePlasticity(const ShellNodes& nodes, ShellFibers& fibers,
                                                         const std::vector<Vec3>& x, double dt) {
  const ShellPlasticity& p = options_.plasticity;
  if (!std::isfinite(p.stretch_yield) && !std::isfinite(p.bend_yield)) {
    return applyPlasticity(fibers, length_, angle_, dt);  // checks the arguments only
  }
  measureFibers(nodes, fibers, x, &length_, &angle_);
  return applyPlasticity(fibers, length_, angle_, dt);
}

ShellMaterialReport ShellMaterialModel::applyPlasticity(ShellFibers& fibers,
                                                        const std::vector<double>& length,
                                                        const std::vector<double>& angle, double dt) {
  const ShellPlasticity& p = options_.plasticity;
  if (!(dt >= 0.0) || p.stretch_creep * dt > 1.0 || p.bend_creep * dt > 1.0) {
    throw std::invalid_argument(
        "ShellMaterialModel::updatePlasticity: need dt >= 0 and creep * dt <= 1 (dt " + std::to_string(dt) +
        ")");
  }
  if (states_.size() != fibers.size()) {
    throw std::invalid_argument("ShellMaterialModel: fiber count differs from the material state");
  }
  ShellMaterialReport report;
  if (!std::isfinite(p.stretch_yield) && !std::isfinite(p.bend_yield)) return report;
  if (length.size() != fibers.size() || angle.size() != fibers.size()) {
    throw std::invalid_argument("ShellMaterialModel: fiber measures do not match the fibers");
  }
  for (size_t q = 0; q < fibers.size(); ++q) {
    Fiber& f = fibers.fibers[q];
    FiberMaterialState& st = states_[q];
    const double dl = length[q] - f.rest_length;
    if (std::abs(dl) > p.stretch_yield * st.original_length) {  // (7.20)
      f.rest_length += p.stretch_creep * dl * dt;               // (7.22)
      ++report.stretch_yielding;
    }
    const double dtheta = angle[q] - f.rest_angle;
    if (std::abs(dtheta) > p.bend_yield) {                // (7.21)
      const double plastic = p.bend_creep * dtheta * dt;  // (7.23)
      f.rest_angle += plastic;
      st.bend_threshold -= p.weakening * st.bend_threshold * std::abs(plastic);  // (7.25)
      st.plastic_bend_total += std::abs(plastic);
      ++report.bend_yielding;
    }
  }
  return report;
}

bool ShellMaterialModel::anyOverloaded(const ShellFibers& fibers, const std::vector<double>& length,
                                       const std::vector<double>& angle) const {
  for (size_t q = 0; q < fibers.size(); ++q) {  // (7.24)
    const Fiber& f = fibers.fibers[q];
    if (length[q] / f.rest_length - 1.0 > states_[q].stretch_threshold ||
        std::abs(angle[q] - f.rest_angle) > states_[q].bend_threshold)
      return true;
  }
  return false;
}

ShellMaterialReport ShellMaterialModel::updateFracture(ShellNodes& nodes, ShellFibers& fibers,
                                                       const std::vector<Vec3>& x, double time) {
  if (states_.size() != fibers.size()) {
    throw std::invalid_argument("ShellMaterialModel: fiber count differs from the material state");
  }
  measureFibers(nodes, fibers, x, &length_, &angle_);
  ShellMaterialReport report;
  report.new_cracks = selectCracks(nodes, fibers, length_, angle_, time);
  if (report.new_cracks > 0) rebuildAfterCracks(nodes, fibers, cracks_.size() - report.new_cracks, &report);
  return report;
}

bool ShellMaterialModel::withinCrackSpeed(const ShellCrack& crack, double time) const {
  const double speed = options_.fracture.max_crack_speed;
  if (!std::isfinite(speed)) return true;
  // Cracks are appended in time order: only the recent ones can be too young.
  for (size_t c = cracks_.size(); c-- > 0;) {
    const ShellCrack& e = cracks_[c];
    const double reach = 2.0 * std::max(e.radius, crack.radius);
    if (time - e.time >= reach / speed) break;
    const double d = (e.center - crack.center).norm();
    if (d < reach && time - e.time < d / speed) return false;
  }
  return true;
}

size_t ShellMaterialModel::selectCracks(const ShellNodes& nodes, const ShellFibers& fibers,
                                        const std::vector<double>& length, const std::vector<double>& angle,
                                        double time) {
  std::vector<std::pair<double, uint32_t>> overloaded;  // (load / threshold, fiber), (7.24)
  std::vector<char> by_stretch(fibers.size(), 0);
  for (size_t q = 0; q < fibers.size(); ++q) {
    const Fiber& f = fibers.fibers[q];
    const double s = (length[q] / f.rest_length - 1.0) / states_[q].stretch_threshold;
    const double b = std::abs(angle[q] - f.rest_angle) / states_[q].bend_threshold;
    if (s > 1.0 || b > 1.0) overloaded.emplace_back(std::max(s, b), static_cast<uint32_t>(q));
    by_stretch[q] = s >= b;
  }
  if (overloaded.empty()) return 0;
  std::sort(overloaded.begin(), overloaded.end(), [](const auto& a, const auto& b) {
    return a.first > b.first || (a.first == b.first && a.second < b.second);
  });
  const std::vector<Vec3>& rest = nodes.rest_positions;
  const size_t first_new = cracks_.size();
  for (const auto& entry : overloaded) {
    if (cracks_.size() - first_new >= options_.fracture.max_cracks_per_step) break;
    const Fiber& f = fibers.fibers[entry.second];
    if (crack_nodes_.count(f.center)) continue;  // one crack per node: a second one would isolate it
    ShellCrack crack;
    crack.node = f.center;
    crack.fiber = entry.second;
    crack.stretch = by_stretch[entry.second] != 0;
    crack.time = time;
    crack.center = rest[f.center];
    crack.normal = restDirection(nodes, f);  // spline tangent at the centre: (x2 - x1) / 2 (B.3)
    const uint32_t* nb = nodes.neighborsOf(f.center);
    for (size_t m = 0; m < nodes.neighborCount(f.center); ++m) {
      crack.radius += (rest[nb[m]] - crack.center).norm() / nodes.neighborCount(f.center);
    }
    bool near = false;
    for (size_t c = first_new; c < cracks_.size(); ++c) {
      near = near || (cracks_[c].center - crack.center).norm() < cracks_[c].radius;
    }
    if (near || !withinCrackSpeed(crack, time)) continue;
    cracks_.push_back(crack);
    crack_nodes_.insert(f.center);
  }
  return cracks_.size() - first_new;
}

void ShellMaterialModel::rebuildAfterCracks(ShellNodes& nodes, ShellFibers& fibers, size_t first_new,
                                            ShellMaterialReport* out) {
  ShellMaterialReport& report = *out;

  // Old fibers by node, to keep those of untouched nodes and to inherit thresholds.
  const ShellFibers old_fibers = fibers;
  const std::vector<FiberMaterialState> old_states = states_;
  const std::vector<uint32_t> dirty =
      recomputeVisibleNeighborhoods(nodes, cracks_, neighbor_count_, first_new);
  report.recomputed_nodes = dirty.size();
  std::vector<char> is_dirty(nodes.size(), 0);
  for (uint32_t i : dirty) is_dirty[i] = 1;
  const double min_length = options_.fracture.min_fiber_length * nodes.spacing;
  fibers.fibers.clear();
  states_.clear();
  for (size_t i = 0; i < nodes.size(); ++i) {
    const size_t o0 = old_fibers.node_offsets[i], o1 = old_fibers.node_offsets[i + 1];
    if (!is_dirty[i]) {
      fibers.fibers.insert(fibers.fibers.end(), old_fibers.fibers.begin() + o0,
                           old_fibers.fibers.begin() + o1);
      states_.insert(states_.end(), old_states.begin() + o0, old_states.begin() + o1);
    } else {
      double gs = options_.fracture.stretch_threshold, gb = options_.fracture.bend_threshold;
      for (size_t q = o0; q < o1; ++q) {
        gs = std::min(gs, old_states[q].stretch_threshold);
        gb = std::min(gb, old_states[q].bend_threshold);
      }
      std::vector<Fiber> made = buildNodeFibers(nodes, i, min_length);
      for (Fiber& f : made) {
        if (stiffness_field_) applyField(nodes, f, stiffness_field_);
        FiberMaterialState st;
        st.original_length = f.rest_length;
        st.original_angle = f.rest_angle;
        st.stretch_threshold = gs;
        st.bend_threshold = gb;
        states_.push_back(st);
        fibers.fibers.push_back(f);
      }
    }
    fibers.node_offsets[i + 1] = fibers.fibers.size();
  }
  report.fiber_delta = static_cast<long>(fibers.size()) - static_cast<long>(old_fibers.size());
}

ShellMaterialReport ShellMaterialModel::update(ShellSolver& solver, double dt) {
  // The solver measured every fiber with its forces at the current positions: no second pass here.
  ShellMaterialReport report =
      applyPlasticity(solver.mutableFibers(), solver.fiberLengths(), solver.fiberAngles(), dt);
  const bool fracture_on = std::isfinite(options_.fracture.stretch_threshold) ||
                           std::isfinite(options_.fracture.bend_threshold) ||
                           std::any_of(states_.begin(), states_.end(), [](const FiberMaterialState& s) {
                             return std::isfinite(s.stretch_threshold) || std::isfinite(s.bend_threshold);
                           });
  if (fracture_on && anyOverloaded(solver.fibers(), solver.fiberLengths(), solver.fiberAngles())) {
    // Cracks are chosen on the solver's own arrays; nodes and fibers are copied only when one is made.
    report.new_cracks = selectCracks(solver.nodes(), solver.fibers(), solver.fiberLengths(),
                                     solver.fiberAngles(), solver.time());
    if (report.new_cracks > 0) {
      ShellNodes nodes = solver.nodes();
      ShellFibers fibers = solver.fibers();
      rebuildAfterCracks(nodes, fibers, cracks_.size() - report.new_cracks, &report);
      solver.setTopology(std::move(nodes), std::move(fibers));
      return report;
    }
  }
  if (report.stretch_yielding + report.bend_yielding > 0) solver.refreshForces();
  return report;
}

}  // namespace rc
