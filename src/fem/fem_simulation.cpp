#include "relaxed_connectivity/fem/fem_simulation.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include <Eigen/Geometry>

#include "relaxed_connectivity/fem/fem_probes.h"
#include "relaxed_connectivity/fem/fem_scene_regions.h"
#include "relaxed_connectivity/fem/polygon_cut.h"

namespace rc {

namespace {

using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// A time in an error message ("%.6g").
std::string timeText(double t) {
  char text[40];
  return std::string(text, std::snprintf(text, sizeof(text), "%.6g", t));
}

// Whether some element of mesh may meet the convex polygon (box: the polygon's bounding box): its bounding
// box meets the polygon's (grown by band) and its nodes are not all farther than band on one side of the
// polygon's plane. Conservative: true for a degenerate polygon (the cut reports the problem).
bool polygonMayMeetElements(const PolyhedralMesh& mesh, const std::vector<Vec3>& polygon,
                            const std::pair<Vec3, Vec3>& box, double band) {
  Vec3 normal = Vec3::Zero();  // Newell
  for (size_t k = 0; k < polygon.size(); ++k) normal += polygon[k].cross(polygon[(k + 1) % polygon.size()]);
  if (!(normal.norm() > 0.0) || !normal.allFinite()) return true;
  normal.normalize();
  const double offset = normal.dot(polygon.front());
  const Vec3 lo = box.first - Vec3::Constant(band), hi = box.second + Vec3::Constant(band);
  for (const ConvexPolyhedron& element : mesh.elements()) {
    Vec3 element_lo = Vec3::Constant(INFINITY), element_hi = Vec3::Constant(-INFINITY);
    double below = INFINITY, above = -INFINITY;
    for (const Vec3& x : element.nodes()) {
      element_lo = element_lo.cwiseMin(x);
      element_hi = element_hi.cwiseMax(x);
      const double d = normal.dot(x) - offset;
      below = std::min(below, d);
      above = std::max(above, d);
    }
    if ((element_lo.array() > hi.array()).any() || (element_hi.array() < lo.array()).any()) continue;
    if (below <= band && above >= -band) return true;
  }
  return false;
}

// Order-independent key of a node set (sum and xor of the ids; equal sets have equal keys).
std::pair<long, int> nodeSetKey(const std::vector<int>& ids, const std::vector<int>* map = nullptr) {
  std::pair<long, int> key(0, 0);
  for (int id : ids) {
    const int v = map ? (*map)[id] : id;
    key.first += v;
    key.second ^= v;
  }
  return key;
}

// Elements of a mesh around each node (compressed rows) and the node set key of each element.
struct NodeElements {
  std::vector<int> offset, elements;
  std::vector<std::pair<long, int>> keys;
  explicit NodeElements(const PolyhedralMesh& mesh) : offset(mesh.numNodes() + 1, 0) {
    for (const ConvexPolyhedron& element : mesh.elements())
      for (int id : element.globalNodeIds()) ++offset[id + 1];
    for (int i = 0; i < mesh.numNodes(); ++i) offset[i + 1] += offset[i];
    elements.resize(offset.back());
    std::vector<int> fill(offset.begin(), offset.end() - 1);
    keys.resize(mesh.numElements());
    for (int e = 0; e < mesh.numElements(); ++e) {
      for (int id : mesh.element(e).globalNodeIds()) elements[fill[id]++] = e;
      keys[e] = nodeSetKey(mesh.element(e).globalNodeIds());
    }
  }
};

// R_e for the elements of `mesh`, cut from `from` (old_node: per node of mesh its node in from's mesh, -1
// for nodes the cut created): the rotation of the old element with the same nodes (elements the cut left
// whole), else of an old element sharing a node (a warm start: R varies smoothly), else I.
std::vector<Eigen::Matrix3d> carriedRotations(const WarpedDynamics& from, const NodeElements& around,
                                              const PolyhedralMesh& mesh, const std::vector<int>& old_node) {
  const PolyhedralMesh& old_mesh = from.model().mesh();
  std::vector<Eigen::Matrix3d> rotations(mesh.numElements(), Eigen::Matrix3d::Identity());
  for (int e = 0; e < mesh.numElements(); ++e) {
    const auto& ids = mesh.element(e).globalNodeIds();
    int first = -1;
    bool all_old = true;
    for (int id : ids) {
      all_old = all_old && old_node[id] >= 0;
      if (first < 0) first = old_node[id];
    }
    if (first < 0) continue;
    int match = around.elements[around.offset[first]];  // some element around the node
    const std::pair<long, int> key = all_old ? nodeSetKey(ids, &old_node) : std::pair<long, int>(-1, 0);
    if (all_old)
      for (int k = around.offset[first]; k < around.offset[first + 1]; ++k) {
        if (around.keys[around.elements[k]] != key) continue;
        const auto& old_ids = old_mesh.element(around.elements[k]).globalNodeIds();
        if (old_ids.size() != ids.size()) continue;
        bool same = true;
        for (size_t a = 0; a < ids.size() && same; ++a)
          same = std::find(old_ids.begin(), old_ids.end(), old_node[ids[a]]) != old_ids.end();
        if (same) {
          match = around.elements[k];
          break;
        }
      }
    rotations[e] = from.rotations()[match];
  }
  return rotations;
}

// Per node of `from`: its dv (the CG warm start) as 3-vectors.
std::vector<Vec3> nodeVelocityIncrements(const WarpedDynamics& from) {
  std::vector<Vec3> dv(from.numNodes());
  for (int i = 0; i < from.numNodes(); ++i) dv[i] = from.previousVelocityIncrement().segment<3>(3 * i);
  return dv;
}

}  // namespace

FemSimulation::FemSimulation(const FemScene& scene) : scene_(scene) {
  if (!scene_.mesh) throw std::invalid_argument("FemSimulation: the scene has no mesh");
  if (scene_.analysis != FemAnalysis::kDynamic)
    throw std::invalid_argument("FemSimulation: '" + scene_.name +
                                "' is a static scene (analysis: static): runFemScene / rc_fem solve it once");
  bodies_.push_back(makeBody(*scene_.mesh, std::vector<Vec3>(scene_.mesh->numNodes(), Vec3::Zero()),
                             scene_.initial_velocities));
  applyLoads();
  applyHeld();
}

std::vector<size_t> FemSimulation::setLoads(std::vector<FemLoad> loads) {
  for (const FemLoad& load : loads)
    if (!load.force.allFinite() || !load.lo.allFinite() || !load.hi.allFinite())
      throw std::invalid_argument("FemSimulation::setLoads: a load with a non-finite box or force");
  const bool had_loads = !scene_.loads.empty();
  scene_.loads = std::move(loads);
  if (scene_.loads.empty() && had_loads)  // remove the forces of the loads before
    for (auto& body : bodies_) body->setExternalForces(Eigen::VectorXd::Zero(body->restPositions().size()));
  return applyLoads();
}

std::vector<size_t> FemSimulation::applyLoads() {
  std::vector<size_t> counts;
  if (scene_.loads.empty()) return counts;
  const double tolerance = femBoxTolerance(*scene_.mesh);
  auto inside = [&](const FemLoad& load, const Vec3& r) { return femSelects(load, r, tolerance); };
  std::vector<Eigen::VectorXd> forces;
  for (const auto& body : bodies_) forces.push_back(Eigen::VectorXd::Zero(body->restPositions().size()));
  for (const FemLoad& load : scene_.loads) {
    size_t count = 0;
    if (load.is_traction) {  // per body: its boundary faces in the box (crack faces too)
      for (size_t b = 0; b < bodies_.size(); ++b) {
        const PolyhedralMesh& mesh = bodies_[b]->model().mesh();
        const Eigen::VectorXd f = femTractionForces(mesh, load, tolerance);
        forces[b] += f;
        for (int i = 0; i < mesh.numNodes(); ++i) count += f.segment<3>(3 * i) != Vec3::Zero();
      }
      counts.push_back(count);
      continue;
    }
    for (const auto& body : bodies_)
      for (Eigen::Index i = 0; i < body->restPositions().size() / 3; ++i)
        count += inside(load, body->restPositions().segment<3>(3 * i));
    counts.push_back(count);
    if (count == 0) continue;  // cut away
    for (size_t b = 0; b < bodies_.size(); ++b)
      for (Eigen::Index i = 0; i < bodies_[b]->restPositions().size() / 3; ++i)
        if (inside(load, bodies_[b]->restPositions().segment<3>(3 * i)))
          forces[b].segment<3>(3 * i) += load.force / double(count);
  }
  for (size_t b = 0; b < bodies_.size(); ++b) bodies_[b]->setExternalForces(forces[b]);
  return counts;
}

std::vector<size_t> FemSimulation::setHeld(std::vector<FemHeldRegion> regions) {
  for (const FemHeldRegion& region : regions) {
    if (!region.lo.allFinite() || !region.hi.allFinite() || !region.displacement.allFinite())
      throw std::invalid_argument("FemSimulation::setHeld: a region with a non-finite box or displacement");
    if (region.in_place && (!region.path.empty() || !region.displacement.isZero()))
      throw std::invalid_argument("FemSimulation::setHeld: an in-place region takes no displacement or path");
    for (size_t k = 0; k < region.path.size(); ++k) {
      if (!std::isfinite(region.path[k].first) || !region.path[k].second.allFinite())
        throw std::invalid_argument("FemSimulation::setHeld: path keyframe " + std::to_string(k) +
                                    " is not finite");
      if (k > 0 && !(region.path[k].first > region.path[k - 1].first))
        throw std::invalid_argument("FemSimulation::setHeld: path times must increase (keyframe " +
                                    std::to_string(k) + ")");
    }
  }
  scene_.held = std::move(regions);
  return applyHeld();
}

std::vector<size_t> FemSimulation::applyHeld() {
  std::vector<size_t> counts(scene_.held.size(), 0);
  const double tolerance = femBoxTolerance(*scene_.mesh);
  held_region_.assign(bodies_.size(), {});
  held_anchor_.assign(bodies_.size(), Eigen::VectorXd());
  for (size_t b = 0; b < bodies_.size(); ++b) {
    const Eigen::VectorXd& rest = bodies_[b]->restPositions();
    std::vector<int> region_of(size_t(rest.size()), -1);
    std::vector<char> mask(size_t(rest.size()), 0);
    for (size_t r = 0; r < scene_.held.size(); ++r) {
      const FemHeldRegion& region = scene_.held[r];
      for (Eigen::Index i = 0; i < rest.size() / 3; ++i) {
        if (!femSelects(region, rest.segment<3>(3 * i), tolerance)) continue;
        ++counts[r];
        for (int k = 0; k < 3; ++k)
          if (region.components[size_t(k)])
            region_of[size_t(3 * i + k)] = int(r), mask[size_t(3 * i + k)] = 1;
      }
    }
    bodies_[b]->setHeld(std::move(mask));
    held_region_[b] = std::move(region_of);
    held_anchor_[b] = bodies_[b]->positions();
  }
  return counts;
}

void FemSimulation::setHeldTargets(double time) {
  for (size_t b = 0; b < bodies_.size(); ++b) {
    if (bodies_[b]->numHeldDofs() == 0) continue;
    std::vector<Vec3> displacement(scene_.held.size());
    for (size_t r = 0; r < scene_.held.size(); ++r) displacement[r] = scene_.held[r].displacementAt(time);
    Eigen::VectorXd targets = bodies_[b]->restPositions();
    for (size_t d = 0; d < held_region_[b].size(); ++d) {
      const int r = held_region_[b][d];
      if (r < 0) continue;
      targets[Eigen::Index(d)] = scene_.held[size_t(r)].in_place
                                     ? held_anchor_[b][Eigen::Index(d)]
                                     : targets[Eigen::Index(d)] + displacement[size_t(r)][int(d % 3)];
    }
    bodies_[b]->setHeldTargets(targets);
  }
}

std::vector<Vec3> FemSimulation::heldReactions() const {
  std::vector<Vec3> sums(scene_.held.size(), Vec3::Zero());
  for (size_t b = 0; b < bodies_.size(); ++b) {
    if (bodies_[b]->numHeldDofs() == 0) continue;
    for (size_t d = 0; d < held_region_[b].size(); ++d)
      if (held_region_[b][d] >= 0)
        sums[size_t(held_region_[b][d])][int(d % 3)] += bodies_[b]->heldReactions()[Eigen::Index(d)];
  }
  return sums;
}

std::unique_ptr<WarpedDynamics> FemSimulation::makeBody(PolyhedralMesh mesh,
                                                        const std::vector<Vec3>& displacements,
                                                        const std::vector<Vec3>& velocities,
                                                        const LinearElasticModel* donor, FemCutReport* report,
                                                        CarriedState* carried) {
  const Clock::time_point start = Clock::now();
  const int n = mesh.numNodes();
  Eigen::VectorXd x(3 * n), v(3 * n);
  for (int i = 0; i < n; ++i) {
    x.segment<3>(3 * i) = mesh.node(i) + displacements[i];
    v.segment<3>(3 * i) = velocities[i];
  }
  LinearElasticModel model(std::move(mesh), scene_.youngs_modulus, scene_.poisson_ratio, scene_.density,
                           scene_.quadrature, donor);
  if (report) {
    report->recomputed_elements += model.numRecomputedElements();
    report->reused_elements += model.numReusedElements();
  }
  auto body = std::make_unique<WarpedDynamics>(std::move(model), scene_.dynamics);
  body->setPositions(x);
  body->setVelocities(v);
  ++retired_counts_.bodies_built;
  if (carried && carry_state_) {
    if (!carried->rotations.empty()) body->setRotations(carried->rotations);
    if (!carried->previous_dv.empty()) {
      Eigen::VectorXd dv(3 * n);
      for (int i = 0; i < n; ++i) dv.segment<3>(3 * i) = carried->previous_dv[i];
      body->setPreviousVelocityIncrement(dv);
    }
  }
  times_.integration += secondsSince(start);
  return body;
}

void FemSimulation::retireSolver(const CholmodSolver* solver) {
  if (!solver) return;
  retired_counts_.analyses += solver->numAnalyses();
  retired_counts_.factorizations += solver->numFactorizations();
  retired_counts_.analysis_seconds += solver->analysisSeconds();
  retired_counts_.factorization_seconds += solver->factorizationSeconds();
}

FemSimulation::SolverCounts FemSimulation::solverCounts() const {
  SolverCounts counts = retired_counts_;
  for (const auto& body : bodies_)
    if (const CholmodSolver* solver = body->cholmodSolver()) {
      counts.analyses += solver->numAnalyses();
      counts.factorizations += solver->numFactorizations();
      counts.analysis_seconds += solver->analysisSeconds();
      counts.factorization_seconds += solver->factorizationSeconds();
    }
  return counts;
}

std::vector<FemBodyState> FemSimulation::bodyStates() const {
  std::vector<FemBodyState> states;
  for (const auto& b : bodies_) states.push_back({&b->model().mesh(), &b->positions(), &b->velocities()});
  return states;
}

int FemSimulation::numNodes() const {
  int n = 0;
  for (const auto& b : bodies_) n += b->numNodes();
  return n;
}

int FemSimulation::numElements() const {
  int n = 0;
  for (const auto& b : bodies_) n += b->model().mesh().numElements();
  return n;
}

double FemSimulation::minGroundDistance() const {
  const GroundPlane& g = scene_.dynamics.ground;
  const Vec3 normal = g.enabled ? g.normal.normalized() : Vec3::UnitZ();
  const double offset = g.enabled ? g.offset : 0.0;
  double d = INFINITY;
  for (const auto& b : bodies_)
    for (int i = 0; i < b->numNodes(); ++i)
      d = std::min(d, normal.dot(b->positions().segment<3>(3 * i)) - offset);
  return d;
}

FemCutReport FemSimulation::applyPolygonCuts(const std::vector<std::vector<Vec3>>& polygons,
                                             double snap_relative_distance, const CutSliverOptions& slivers) {
  FemCutReport report;
  report.polygons = static_cast<int>(polygons.size());
  polygons_applied_ += report.polygons;
  std::vector<std::pair<Vec3, Vec3>> boxes;  // per polygon
  for (const auto& polygon : polygons) {
    Vec3 lo = Vec3::Constant(INFINITY), hi = Vec3::Constant(-INFINITY);
    for (const Vec3& p : polygon) {
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
    boxes.emplace_back(lo, hi);
  }
  PolygonCutOptions options;
  options.snap_relative_distance = snap_relative_distance;
  options.slivers = slivers;
  std::vector<std::unique_ptr<WarpedDynamics>> next;
  for (auto& body : bodies_) {
    Clock::time_point start = Clock::now();
    const PolyhedralMesh& mesh = body->model().mesh();
    Vec3 lo = Vec3::Constant(INFINITY), hi = Vec3::Constant(-INFINITY);
    for (const Vec3& x : mesh.nodes()) {
      lo = lo.cwiseMin(x);
      hi = hi.cwiseMax(x);
    }
    const double margin = 1e-9 * (hi - lo).norm();
    std::vector<int> hits;
    for (size_t k = 0; k < boxes.size(); ++k)
      if ((boxes[k].first.array() <= hi.array() + margin).all() &&
          (boxes[k].second.array() >= lo.array() - margin).all())
        hits.push_back(static_cast<int>(k));
    // Keep only polygons that an element may meet: an element whose box meets the polygon's and whose nodes
    // are not all (beyond a margin) on one side of its plane. Saves building a ProgressiveCutMesh when
    // the blade has not reached the body yet.
    const double band = std::max(10.0 * snap_relative_distance, 1e-6) * (hi - lo).norm();
    hits.erase(
        std::remove_if(hits.begin(), hits.end(),
                       [&](int k) { return !polygonMayMeetElements(mesh, polygons[k], boxes[k], band); }),
        hits.end());
    if (hits.empty()) {
      times_.topology += secondsSince(start);
      next.push_back(std::move(body));
      continue;
    }
    const int n = mesh.numNodes();
    std::vector<Vec3> u(n), v(n);
    for (int i = 0; i < n; ++i) {
      u[i] = body->positions().segment<3>(3 * i) - mesh.node(i);
      v[i] = body->velocities().segment<3>(3 * i);
    }
    ProgressiveCutMesh cut_mesh(mesh, u, options);
    PolygonCutStats total;
    for (int k : hits) {
      const PolygonCutStats s = cut_mesh.cut(polygons[k]);
      total.num_split_elements += s.num_split_elements;
      total.num_new_nodes += s.num_new_nodes + s.num_pocket_nodes;
      total.num_duplicated_nodes += s.num_duplicated_nodes;
      total.num_new_crack_faces += s.num_new_crack_faces;
      report.slivers_removed += s.slivers.num_removed;
      report.slivers_kept += s.slivers.num_rejected;
    }
    if (total.num_split_elements == 0 && total.num_new_nodes == 0 && total.num_new_crack_faces == 0) {
      times_.topology += secondsSince(start);
      next.push_back(std::move(body));
      continue;
    }
    ++report.bodies_cut;
    report.split_elements += total.num_split_elements;
    report.new_nodes += total.num_new_nodes;
    report.duplicated_nodes += total.num_duplicated_nodes;
    report.crack_faces += total.num_new_crack_faces;
    const std::vector<Vec3> cut_velocities = cut_mesh.interpolateNodeValues(v);
    int num_components = 0;
    cut_mesh.elementComponents(&num_components);
    if (num_components > 1) ++report.bodies_separated;
    const std::vector<Vec3> cut_dv = cut_mesh.interpolateNodeValues(nodeVelocityIncrements(*body));
    const NodeElements around(mesh);
    std::vector<PolyhedralMesh> meshes;
    std::vector<std::vector<Vec3>> side_u, side_v;
    std::vector<CarriedState> carried(num_components);
    for (int c = 0; c < num_components; ++c) {
      std::vector<int> ids;
      meshes.push_back(cut_mesh.componentMesh(c, &ids, &mesh));
      side_u.emplace_back();
      side_v.emplace_back();
      std::vector<int> old_node(ids.size());
      for (size_t k = 0; k < ids.size(); ++k) {
        const int id = ids[k];
        side_u.back().push_back(cut_mesh.displacements()[id]);
        side_v.back().push_back(cut_velocities[id]);
        carried[c].previous_dv.push_back(cut_dv[id]);
        int original = id;  // follow duplicates back to a node of the cut body (-1: created by the cut)
        while (original >= cut_mesh.numInitialNodes()) original = cut_mesh.duplicateOf()[original];
        old_node[k] = original;
      }
      carried[c].rotations = carriedRotations(*body, around, meshes.back(), old_node);
    }
    times_.topology += secondsSince(start);
    for (int c = 0; c < num_components; ++c)
      next.push_back(
          makeBody(std::move(meshes[c]), side_u[c], side_v[c], &body->model(), &report, &carried[c]));
    retireSolver(body->cholmodSolver());
  }
  bodies_ = std::move(next);
  applyLoads();
  applyHeld();
  recomputed_elements_ += report.recomputed_elements;
  reused_elements_ += report.reused_elements;
  slivers_removed_ += report.slivers_removed;
  slivers_kept_ += report.slivers_kept;
  return report;
}

FemCutReport FemSimulation::applyCut(const FemSceneCut& cut) {
  if (cut.isPolygonCut()) return applyPolygonCuts(cut.polygons, cut.snap_relative_distance, cut.slivers);
  FemCutReport report;
  std::vector<std::unique_ptr<WarpedDynamics>> next;
  PlaneCutOptions options;
  options.region = cut.region;
  options.snap_relative_distance = cut.snap_relative_distance;
  options.slivers = cut.slivers;
  for (auto& body : bodies_) {
    Clock::time_point start = Clock::now();
    const PolyhedralMesh& mesh = body->model().mesh();
    const int n = mesh.numNodes();
    std::vector<Vec3> u(n), v(n);
    for (int i = 0; i < n; ++i) {
      u[i] = body->positions().segment<3>(3 * i) - mesh.node(i);
      v[i] = body->velocities().segment<3>(3 * i);
    }
    // Bodies entirely on one side (the plane misses or only touches them) stay as they are.
    bool negative = false, positive = false;
    for (const Vec3& x : mesh.nodes()) {
      const double d = cut.normal.dot(x - cut.point);
      negative = negative || d < 0;
      positive = positive || d > 0;
    }
    if (!(negative && positive)) {
      times_.topology += secondsSince(start);
      next.push_back(std::move(body));
      continue;
    }
    PlaneCutResult result = cutMeshByPlane(mesh, u, cut.point, cut.normal, options);
    bool side_negative = false, side_positive = false, crossed_whole = false;
    for (int s : result.element_side) {
      side_negative = side_negative || s < 0;
      side_positive = side_positive || s > 0;
      crossed_whole = crossed_whole || s == 0;
    }
    if (result.num_split_elements == 0 &&
        !(side_negative && side_positive && cut.separate && !crossed_whole)) {
      times_.topology += secondsSince(start);  // snapped onto existing nodes only: nothing changes
      next.push_back(std::move(body));
      continue;
    }
    ++report.bodies_cut;
    report.split_elements += result.num_split_elements;
    report.new_nodes += result.num_new_nodes;
    report.slivers_removed += result.slivers.num_removed;
    report.slivers_kept += result.slivers.num_rejected;
    const std::vector<Vec3> cut_velocities = interpolateCutValues(mesh, result, v);
    const std::vector<Vec3> cut_dv = interpolateCutValues(mesh, result, nodeVelocityIncrements(*body));
    if (cut.separate && side_negative && side_positive && !crossed_whole) {
      const SeparatedMesh separated = separateAlongPlane(result);
      ++report.bodies_separated;
      report.duplicated_nodes += separated.numDuplicatedNodes();
      const int cut_nodes = result.mesh.numNodes();
      auto combined = [&](const std::vector<Vec3>& values, int id) {
        return id < cut_nodes ? values[id] : values[separated.duplicate_of[id - cut_nodes]];
      };
      std::vector<std::vector<Vec3>> side_u(2), side_v(2);
      std::vector<CarriedState> carried(2);
      for (int s = 0; s < 2; ++s) {
        for (int id : separated.side_node_ids[s]) {
          side_u[s].push_back(combined(result.displacements, id));
          side_v[s].push_back(combined(cut_velocities, id));
          carried[s].previous_dv.push_back(combined(cut_dv, id));
        }
        for (int e : separated.side_element_ids[s])
          carried[s].rotations.push_back(body->rotations()[result.parent_element[e]]);
      }
      times_.topology += secondsSince(start);
      for (int s = 0; s < 2; ++s)
        next.push_back(
            makeBody(separated.sides[s], side_u[s], side_v[s], &body->model(), &report, &carried[s]));
    } else {
      CarriedState carried;
      carried.previous_dv = cut_dv;
      for (int parent : result.parent_element) carried.rotations.push_back(body->rotations()[parent]);
      times_.topology += secondsSince(start);
      next.push_back(makeBody(std::move(result.mesh), result.displacements, cut_velocities, &body->model(),
                              &report, &carried));
    }
    retireSolver(body->cholmodSolver());
  }
  bodies_ = std::move(next);
  applyLoads();
  applyHeld();
  recomputed_elements_ += report.recomputed_elements;
  reused_elements_ += report.reused_elements;
  slivers_removed_ += report.slivers_removed;
  slivers_kept_ += report.slivers_kept;
  return report;
}

void FemSimulation::step() {
  const double dt = scene_.dynamics.time_step;
  const double now = time_ + 1e-9 * dt;
  // Polygons due now are applied together (one ProgressiveCutMesh per body and step).
  std::vector<std::vector<Vec3>> batch;
  double batch_snap = 0.0;
  CutSliverOptions batch_slivers;
  int batch_cut = -1;
  auto flush = [&]() {
    if (batch.empty()) return;
    try {
      applyPolygonCuts(batch, batch_snap, batch_slivers);
    } catch (const std::exception& e) {
      throw std::runtime_error("cut " + std::to_string(batch_cut) +
                               " (polygons due at t = " + timeText(time_) + "): " + e.what());
    }
    batch.clear();
  };
  while (next_cut_ < static_cast<int>(scene_.cuts.size())) {
    const FemSceneCut& cut = scene_.cuts[next_cut_];
    if (!cut.isPolygonCut()) {
      if (cut.time > now) break;
      flush();
      try {
        applyCut(cut);
      } catch (const std::exception& e) {
        throw std::runtime_error("cut " + std::to_string(next_cut_) + " (t = " + timeText(cut.time) +
                                 "): " + e.what());
      }
      ++next_cut_;
      continue;
    }
    if (!batch.empty() &&
        (batch_snap != cut.snap_relative_distance || batch_slivers.enabled != cut.slivers.enabled ||
         batch_slivers.relative_thickness != cut.slivers.relative_thickness))
      flush();
    while (next_polygon_ < static_cast<int>(cut.polygons.size()) && cut.polygonTime(next_polygon_) <= now) {
      if (batch.empty()) {
        batch_snap = cut.snap_relative_distance;
        batch_slivers = cut.slivers;
        batch_cut = next_cut_;
      }
      batch.push_back(cut.polygons[next_polygon_++]);
    }
    if (next_polygon_ < static_cast<int>(cut.polygons.size())) break;
    next_polygon_ = 0;
    ++next_cut_;
  }
  flush();
  const Clock::time_point start = Clock::now();
  if (!scene_.held.empty()) setHeldTargets(time_ + dt);
  int iterations = 0;
  for (auto& body : bodies_) {
    const StepStatistics stats = body->step();
    times_.rotations += 1e-3 * stats.warping_ms;
    times_.assembly += 1e-3 * stats.assembly_ms;
    times_.solve += 1e-3 * stats.solve_ms;
    iterations += stats.solver_iterations;
    if (!stats.converged) ++unconverged_;
    if (!body->positions().allFinite() || !body->velocities().allFinite())
      throw std::runtime_error("step " + std::to_string(steps_ + 1) + ": the state became non-finite");
  }
  times_.dynamics += secondsSince(start);
  solver_iterations_ += iterations;
  max_step_iterations_ = std::max(max_step_iterations_, iterations);
  ++steps_;
  time_ = steps_ * dt;
}

}  // namespace rc
