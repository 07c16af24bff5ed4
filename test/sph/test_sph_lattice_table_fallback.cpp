// The fallback paths for lattice points outside the tables of lattice offsets [-8, 8)^3: the hash table of
// assignLatticePoints (8.21) and DockTable::findOutside of the docking (8.2.5). Far points arise when h
// exceeds about 6.5 d (lattice index 8 is reached at |r| = 6.93 d in 2D, 6.56 d in 3D; h = 7.2 d, 6.7 d). The
// same relative geometry is put inside and outside the table by the lattice's point symmetry n -> -n: the
// table is asymmetric (index -8 inside, +8 outside), so an inverted lattice orientation moves the far points
// into the table and others out of it; every decision must come out the same.
#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "relaxed_connectivity/sph/sph_elastic_solid.h"

namespace rc {
namespace {

constexpr int kHalf = SphLatticeAssignment::kTableHalfWidth;

bool outsideTable(const Eigen::Vector3i& n) {
  return n.minCoeff() < -kHalf || n.maxCoeff() >= kHalf;
}

/// (8.21) by brute force: nearest lattice point of A^-1 r over a window of indices, one neighbour per point
/// (the closest; ties: the lower index), the origin left to the centre.
void referenceAssignment(const SphLattice& lattice, const Eigen::Matrix3d& transform,
                         const std::vector<Vec3>& offsets, std::vector<Eigen::Vector3i>& indices,
                         std::vector<uint8_t>& assigned, std::vector<double>& sq_dists) {
  const size_t n = offsets.size();
  const int dim = lattice.dimension();
  indices.resize(n);
  sq_dists.resize(n);
  const Eigen::Matrix3d inverse = transform.inverse();
  for (size_t k = 0; k < n; ++k) {
    Vec3 q = inverse * offsets[k];
    if (dim == 2) q.z() = 0.0;
    const Vec3 c = lattice.inverseBasis() * q;
    const Eigen::Vector3i base(int(std::lround(c.x())), int(std::lround(c.y())),
                               dim == 3 ? int(std::lround(c.z())) : 0);
    double best = std::numeric_limits<double>::infinity();
    const int kz = dim == 3 ? 2 : 0;
    for (int dk = -kz; dk <= kz; ++dk)
      for (int dj = -2; dj <= 2; ++dj)
        for (int di = -2; di <= 2; ++di) {
          const Eigen::Vector3i m = base + Eigen::Vector3i(di, dj, dk);
          const double d2 = (lattice.point(m) - q).squaredNorm();
          if (d2 < best) {
            best = d2;
            indices[k] = m;
          }
        }
    sq_dists[k] = best;
  }
  assigned.assign(n, 1);
  for (size_t k = 0; k < n; ++k) {
    if (indices[k].isZero()) assigned[k] = 0;
    for (size_t o = 0; o < n; ++o)
      if (o != k && indices[o] == indices[k] &&
          (sq_dists[o] < sq_dists[k] || (sq_dists[o] == sq_dists[k] && o < k)))
        assigned[k] = 0;
  }
}

/// Offsets of a neighbourhood of a particle with lattice transform `transform`: near points (all indices in
/// [-7, 7]), points at index -8 (inside the table) and +8 (outside), and far groups (|index| 9..12) in which
/// up to four neighbours compete for one lattice point at distinct distances, plus exact duplicates (ties).
/// Every jitter is below 0.3 d, so each neighbour's nearest lattice point is its construction point.
std::vector<Vec3> makeOffsets(const SphLattice& lattice, const Eigen::Matrix3d& transform,
                              std::mt19937_64& rng, size_t* far_count) {
  const int dim = lattice.dimension();
  const double d = lattice.spacing();
  std::uniform_int_distribution<int> near_index(-7, 7), far_index(9, 12), sign(0, 1);
  std::uniform_real_distribution<double> uni(-1.0, 1.0);
  int counter = 0;  // distinct jitter lengths: no near-ties between different offsets
  const auto jitter = [&](double length) -> Vec3 {
    Vec3 u(uni(rng), uni(rng), dim == 3 ? uni(rng) : 0.0);
    if (u.norm() < 1e-3) u = Vec3::UnitX();
    return (length + 0.0005 * counter++) * d * u.normalized();
  };
  const auto offsetOf = [&](const Eigen::Vector3i& n, double length) -> Vec3 {
    return Vec3(transform * (lattice.point(n) + jitter(length)));
  };
  std::vector<Vec3> offsets;
  *far_count = 0;
  for (int t = 0; t < 40; ++t) {  // near, with competitors
    const Eigen::Vector3i n(near_index(rng), near_index(rng), dim == 3 ? near_index(rng) : 0);
    offsets.push_back(offsetOf(n, 0.05 + 0.2 * (t % 2)));
    if (t % 4 == 0) offsets.push_back(offsetOf(n, 0.15));
  }
  for (int t = 0; t < 12; ++t) {  // the rim of the table: -8 inside, +8 outside
    Eigen::Vector3i n(near_index(rng), near_index(rng), dim == 3 ? near_index(rng) : 0);
    n[t % dim] = t % 2 ? kHalf : -kHalf;
    offsets.push_back(offsetOf(n, 0.1));
    offsets.push_back(offsetOf(n, 0.2));  // competes for the same point, farther
    *far_count += 2 * outsideTable(n);
  }
  for (int t = 0; t < 10; ++t) {  // far groups competing for one point each
    Eigen::Vector3i n(near_index(rng), near_index(rng), dim == 3 ? near_index(rng) : 0);
    n[t % dim] = (sign(rng) ? 1 : -1) * far_index(rng);
    const int group = 2 + t % 3;
    for (int g = 0; g < group; ++g) offsets.push_back(offsetOf(n, 0.25 - 0.06 * g));  // later ones closer
    if (t % 2 == 0) offsets.push_back(offsets.back());  // an exact tie: the lower index keeps it
    *far_count += group + (t % 2 == 0);
  }
  offsets.push_back(Vec3(transform * jitter(0.1)));  // the centre's own point
  std::shuffle(offsets.begin(), offsets.end(), rng);
  return offsets;
}

void checkAssignmentFallback(int dim) {
  const SphLattice lattice(dim, 0.05);
  std::mt19937_64 rng(17 + dim);
  SphLatticeAssignment shared;  // reused across in-table and fallback calls (stamps)
  size_t fallback_calls = 0, far_total = 0, far_assigned = 0, far_lost = 0;
  for (int trial = 0; trial < 40; ++trial) {
    SCOPED_TRACE("dimension " + std::to_string(dim) + " trial " + std::to_string(trial));
    Eigen::Matrix3d transform = Eigen::Matrix3d::Identity();
    if (trial > 0) {
      std::uniform_real_distribution<double> uni(-1.0, 1.0);
      const Vec3 axis = dim == 3 ? Vec3(uni(rng), uni(rng), 1.0).normalized() : Vec3::UnitZ();
      transform = Eigen::AngleAxisd(0.7 * trial, axis).toRotationMatrix();
      transform.col(0) *= 1.0 + 0.02 * (trial % 7);  // a stretched neighbourhood
    }
    size_t far_count = 0;
    std::vector<Vec3> offsets = makeOffsets(lattice, transform, rng, &far_count);
    ASSERT_GT(far_count, 20u);
    if (trial % 3 == 1) {  // a far neighbour first: the table pass stops at once
      for (size_t k = 0; k < offsets.size(); ++k) {
        const Eigen::Vector3i n = lattice.nearestIndex(Vec3(transform.inverse() * offsets[k]));
        if (outsideTable(n)) {
          std::swap(offsets[0], offsets[k]);
          break;
        }
      }
    }
    std::vector<Eigen::Vector3i> ref_indices;
    std::vector<uint8_t> ref_assigned;
    std::vector<double> ref_d2;
    referenceAssignment(lattice, transform, offsets, ref_indices, ref_assigned, ref_d2);
    SphLatticeAssignment fresh;
    assignLatticePoints(lattice, transform, offsets, fresh);
    assignLatticePoints(lattice, transform, offsets, shared);
    fallback_calls += fresh.keepers.size() >= 4 * offsets.size();  // the hash table was built
    for (size_t k = 0; k < offsets.size(); ++k) {
      ASSERT_EQ(fresh.indices[k], ref_indices[k]) << "neighbour " << k;
      ASSERT_EQ(fresh.assigned[k], ref_assigned[k])
          << "neighbour " << k << " index " << ref_indices[k].transpose();
      ASSERT_NEAR(fresh.sq_dists[k], ref_d2[k], 1e-12 * lattice.spacing() * lattice.spacing());
      ASSERT_EQ(shared.indices[k], fresh.indices[k]);
      ASSERT_EQ(shared.assigned[k], fresh.assigned[k]);
      if (outsideTable(ref_indices[k])) {
        ++far_total;
        (ref_assigned[k] ? far_assigned : far_lost) += 1;
      }
    }
    // The in-table neighbours alone take the table path (no hash table) and keep the same decisions: far
    // points compete only among themselves.
    std::vector<Vec3> near;
    std::vector<size_t> near_of;
    for (size_t k = 0; k < offsets.size(); ++k)
      if (!outsideTable(ref_indices[k])) {
        near.push_back(offsets[k]);
        near_of.push_back(k);
      }
    SphLatticeAssignment table_only;
    assignLatticePoints(lattice, transform, near, table_only);
    EXPECT_TRUE(table_only.keepers.empty());  // no fallback
    assignLatticePoints(lattice, transform, near, shared);
    for (size_t k = 0; k < near.size(); ++k) {
      ASSERT_EQ(table_only.indices[k], fresh.indices[near_of[k]]);
      ASSERT_EQ(table_only.assigned[k], fresh.assigned[near_of[k]]);
      ASSERT_EQ(table_only.sq_dists[k], fresh.sq_dists[near_of[k]]);
      ASSERT_EQ(shared.assigned[k], fresh.assigned[near_of[k]]);
    }
    // The inverted neighbourhood: indices n -> -n, so the +8 points enter the table and the -8 points
    // leave it; the decisions are the same.
    std::vector<Vec3> inverted(offsets.size());
    for (size_t k = 0; k < offsets.size(); ++k) inverted[k] = -offsets[k];
    SphLatticeAssignment mirrored;
    assignLatticePoints(lattice, transform, inverted, mirrored);
    for (size_t k = 0; k < offsets.size(); ++k) {
      ASSERT_EQ(mirrored.indices[k], Eigen::Vector3i(-fresh.indices[k]));
      ASSERT_EQ(mirrored.assigned[k], fresh.assigned[k]);
      ASSERT_EQ(mirrored.sq_dists[k], fresh.sq_dists[k]);
    }
  }
  EXPECT_EQ(fallback_calls, 40u);  // every call took the fallback path
  EXPECT_GT(far_total, 1000u);
  EXPECT_GT(far_assigned, 200u);  // far points kept by their closest neighbour
  EXPECT_GT(far_lost, 100u);      // and lost by the competitors
}

TEST(SphLatticeTableFallback, AssignmentOfFarPointsMatchesReferenceAndTable) {
  checkAssignmentFallback(2);
  checkAssignmentFallback(3);
}

// --- Docking (8.2.5) with lattice points outside the DockTable ---

constexpr double kSpacing = 0.02;
constexpr double kH = 7.2 * kSpacing;  // 2D: lattice indices up to +-8 within h
constexpr double kDt = 1e-3;

/// Hexagonal block, about 16 x 16 spacings.
std::vector<Vec3> restBlock() {
  return sampleLatticeBox(SphLattice(2, kSpacing), Vec3::Zero(), Vec3(15.0 * kSpacing, 15.0 * kSpacing, 0.0));
}

/// Fracture at once (infinite rate) and docking with probability 1 within a step (rate cap 1e6/s reached
/// in 1 us: exp(-999) = 0): every docking decision is deterministic, independent of the random keys.
SphElasticConfig dockingConfig() {
  SphElasticConfig e;
  e.lattice_spacing = kSpacing;
  e.goal_stiffness = 1.0e4;
  e.time_step = kDt;
  e.docking = true;
  e.fracture_strain = 0.08;
  e.max_docking_rate = 1.0e6;
  e.docking_rate_increase = 1.0e12;
  e.docking_rate_decrease = 1.0e5;
  return e;
}

/// Number of ordered pairs (i, j) within h at rest, and of those whose lattice offset (orientation `q`)
/// lies outside the table.
void countPairs(const std::vector<Vec3>& x, const Eigen::Matrix3d& q, size_t* pairs, size_t* far) {
  const SphLattice lattice(2, kSpacing);
  *pairs = *far = 0;
  for (size_t i = 0; i < x.size(); ++i)
    for (size_t j = 0; j < x.size(); ++j) {
      const double dx = x[j].x() - x[i].x(), dy = x[j].y() - x[i].y(), dz = x[j].z() - x[i].z();
      if (i == j || !(dx * dx + dy * dy + dz * dz < kH * kH)) continue;
      ++*pairs;
      *far += outsideTable(lattice.nearestIndex(Vec3(q.transpose() * (x[j] - x[i]))));
    }
}

/// Prescribed motion of the block at evaluation e: rest, a stretch in x beyond the fracture strain and back,
/// then a crack (the right half moved away by up to 2.4 d) that closes again.
std::vector<Vec3> deformed(const std::vector<Vec3>& rest, int e) {
  const double centre = 7.5 * kSpacing;
  double stretch = 1.0, gap = 0.0;
  if (e >= 2 && e <= 7) stretch = 1.0 + 0.03 * (e - 1);
  if (e >= 8 && e <= 13) stretch = 1.18 - 0.03 * (e - 7);
  if (e >= 14 && e <= 17) gap = 0.6 * kSpacing * (e - 13);
  if (e >= 18 && e <= 21) gap = 2.4 * kSpacing - 0.6 * kSpacing * (e - 17);
  std::vector<Vec3> x = rest;
  for (Vec3& p : x) {
    const bool right = p.x() > centre;
    p.x() = centre + stretch * (p.x() - centre) + (right ? gap : 0.0);
  }
  return x;
}

struct DockingRun {
  std::vector<SphElasticStats> stats;
  std::vector<std::vector<Vec3>> forces;
};

constexpr int kEvaluations = 30;

DockingRun runPrescribed(const Eigen::Matrix3d& orientation, const std::vector<Vec3>& rest) {
  const SphKernels kernels(2, kH);
  SphElasticSolid solid(dockingConfig(), kernels, 1, orientation);
  SphParticles particles;
  solid.addParticles(particles, rest, 1.0);
  DockingRun run;
  std::vector<Vec3> forces;
  for (int e = 0; e < kEvaluations; ++e) {
    particles.positions = deformed(rest, e);
    solid.computeForces(particles, forces);
    run.stats.push_back(solid.stats());
    run.forces.push_back(forces);
  }
  return run;
}

/// The lattice inverted (a rotation by pi about z): the same particles, every lattice offset n -> -n.
Eigen::Matrix3d inversion() {
  return Vec3(-1.0, -1.0, 1.0).asDiagonal();
}

TEST(SphLatticeTableFallback, FarPointsExistInBothOrientations) {
  const std::vector<Vec3> rest = restBlock();
  size_t pairs = 0, far = 0, pairs_inv = 0, far_inv = 0, far_both = 0;
  countPairs(rest, Eigen::Matrix3d::Identity(), &pairs, &far);
  countPairs(rest, inversion(), &pairs_inv, &far_inv);
  const SphLattice lattice(2, kSpacing);
  for (size_t i = 0; i < rest.size(); ++i)
    for (size_t j = 0; j < rest.size(); ++j) {
      const Vec3 r = rest[j] - rest[i];
      if (i == j || !(r.squaredNorm() < kH * kH)) continue;
      const Eigen::Vector3i n = lattice.nearestIndex(r);
      far_both += outsideTable(n) && outsideTable(Eigen::Vector3i(-n));
    }
  EXPECT_EQ(pairs, pairs_inv);
  EXPECT_GT(far, 200u);     // offsets with a +8 index: the fallback of identity orientation
  EXPECT_EQ(far_inv, far);  // the pair (j, i) of each (i, j)
  EXPECT_EQ(far_both, 0u);  // no pair lies outside the table in both: every far pair is in it once
  EXPECT_GT(pairs, 30000u);
}

TEST(SphLatticeTableFallback, DockingAtRestKeepsFarPointsDocked) {
  // Every pair within h docks at the first evaluation and stays docked while at rest: a far point that the
  // fallback lookup failed to find would separate and dock anew (separated, redocked > 0).
  const std::vector<Vec3> rest = restBlock();
  size_t pairs = 0, far = 0;
  countPairs(rest, Eigen::Matrix3d::Identity(), &pairs, &far);
  for (const Eigen::Matrix3d& q : {Eigen::Matrix3d(Eigen::Matrix3d::Identity()), inversion()}) {
    const SphKernels kernels(2, kH);
    SphElasticSolid solid(dockingConfig(), kernels, 1, q);
    SphParticles particles;
    solid.addParticles(particles, rest, 1.0);
    std::vector<Vec3> forces;
    for (int e = 0; e < 4; ++e) {
      solid.computeForces(particles, forces);
      const SphElasticStats& st = solid.stats();
      EXPECT_EQ(st.docked_points, pairs) << "evaluation " << e;
      EXPECT_EQ(st.assigned_pairs, pairs);
      EXPECT_EQ(st.detached, 0u);
      EXPECT_EQ(st.separated, 0u);
      EXPECT_EQ(st.redocked, 0u);
    }
  }
}

TEST(SphLatticeTableFallback, DockingCountsAgreeInsideAndOutsideTable) {
  const std::vector<Vec3> rest = restBlock();
  const DockingRun plain = runPrescribed(Eigen::Matrix3d::Identity(), rest);
  const DockingRun inverted = runPrescribed(inversion(), rest);
  const DockingRun again = runPrescribed(Eigen::Matrix3d::Identity(), rest);
  uint64_t detached = 0, separated = 0, redocked = 0;
  for (int e = 0; e < kEvaluations; ++e) {
    SCOPED_TRACE("evaluation " + std::to_string(e));
    const SphElasticStats &a = plain.stats[e], &b = inverted.stats[e];
    EXPECT_EQ(a.docked_points, b.docked_points);
    EXPECT_EQ(a.detached, b.detached);
    EXPECT_EQ(a.separated, b.separated);
    EXPECT_EQ(a.redocked, b.redocked);
    EXPECT_EQ(a.assigned_pairs, b.assigned_pairs);
    EXPECT_EQ(a.unassigned_pairs, b.unassigned_pairs);
    EXPECT_EQ(again.stats[e].docked_points, a.docked_points);
    EXPECT_TRUE(again.forces[e] == plain.forces[e]);  // deterministic, bitwise
    if (e > 0) {  // every docked point stays, detaches or separates; every new one is redocked
      EXPECT_EQ(a.docked_points + a.detached + a.separated, plain.stats[e - 1].docked_points + a.redocked);
    }
    detached += a.detached;
    separated += a.separated;
    redocked += a.redocked;
  }
  EXPECT_GT(detached, 1000u);
  EXPECT_GT(separated, 100u);
  EXPECT_GT(redocked, 1000u);
}

TEST(SphLatticeTableFallback, DockingAtRestKeepsFarPointsDocked3d) {
  // fcc: lattice index 8 is reached at |r| = 6.56 d, inside h = 6.7 d.
  const double h = 6.7 * kSpacing;
  const SphLattice lattice(3, kSpacing);
  const std::vector<Vec3> rest = sampleLatticeBox(lattice, Vec3::Zero(), Vec3::Constant(7.5 * kSpacing));
  size_t pairs = 0, far = 0;
  for (size_t i = 0; i < rest.size(); ++i)
    for (size_t j = 0; j < rest.size(); ++j) {
      const double dx = rest[j].x() - rest[i].x(), dy = rest[j].y() - rest[i].y(),
                   dz = rest[j].z() - rest[i].z();
      if (i == j || !(dx * dx + dy * dy + dz * dz < h * h)) continue;
      ++pairs;
      far += outsideTable(lattice.nearestIndex(rest[j] - rest[i]));
    }
  EXPECT_GT(far, 50u);
  const SphKernels kernels(3, h);
  SphElasticSolid solid(dockingConfig(), kernels, 1);
  SphParticles particles;
  solid.addParticles(particles, rest, 1.0);
  std::vector<Vec3> forces;
  for (int e = 0; e < 3; ++e) {
    solid.computeForces(particles, forces);
    const SphElasticStats& st = solid.stats();
    EXPECT_EQ(st.docked_points, pairs) << "evaluation " << e;
    EXPECT_EQ(st.detached + st.separated + st.redocked, 0u) << "evaluation " << e;
  }
}

}  // namespace
}  // namespace rc
