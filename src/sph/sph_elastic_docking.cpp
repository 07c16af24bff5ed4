// Fracture, docking and healing of SphElasticSolid (thesis 8.2.5): the per-neighbourhood update of which
// lattice points are docked, with the Poisson event probabilities (8.34) and the docking rates.
#include <algorithm>
#include <cmath>

#include <Eigen/Dense>

#include "relaxed_connectivity/sph/sph_elastic_solid.h"
#include "relaxed_connectivity/sph/sph_lattice_keys.h"

namespace rc {

namespace {

using Mat3 = Eigen::Matrix3d;

uint64_t splitMix64(uint64_t x) {
  x += 0x9E3779B97F4A7C15ULL;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ULL;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBULL;
  return x ^ (x >> 31);
}

/// Probability of a Poisson event of `rate` within dt (8.34); an infinite rate gives 1.
double eventProbability(double rate, double dt) {
  return std::isinf(rate) ? 1.0 : -std::expm1(-rate * dt);
}

}  // namespace

double SphElasticSolid::uniformRandom(uint64_t seed, uint64_t evaluation, uint64_t particle, uint64_t key) {
  uint64_t x = splitMix64(seed ^ 0x5DEECE66DULL);
  x = splitMix64(x ^ evaluation);
  x = splitMix64(x ^ (particle * 0xD6E8FEB86659FD93ULL));
  x = splitMix64(x ^ (key * 0x9E3779B97F4A7C15ULL));
  return double(x >> 11) * 0x1.0p-53;
}

SphElasticSolid::RateStep SphElasticSolid::growDockingRate(double rate, double growth, double cap,
                                                           double dt) {
  const double grown = rate + growth * dt;
  if (grown <= cap) return {grown, (rate + 0.5 * growth * dt) * dt};
  // The rate reaches the cap after t = (cap - rate) / growth and stays there for the rest of the step.
  const double t = rate < cap ? (cap - rate) / growth : 0.0;
  return {cap, 0.5 * (rate + cap) * t + cap * (dt - t)};
}

bool SphElasticSolid::dockedInnerNeighbor(const std::vector<DockPoint>& state, const DockTable& table,
                                          const Eigen::Vector3i& index) const {
  const double d2 = lattice_.spacing() * lattice_.spacing(), eps = 1e-9 * d2;
  const double norm2 = lattice_.point(index).squaredNorm();
  for (const Eigen::Vector3i& step : nearest_steps_) {  // |B step| = d
    const Eigen::Vector3i inner = index + step;
    if (!(lattice_.point(inner).squaredNorm() < norm2 - eps)) continue;
    if (inner.isZero()) return true;  // next to the centre particle
    const int32_t entry = table.find(state, latticeTableSlot(inner), latticeKey(inner));
    if (entry >= 0 && state[size_t(entry)].docked) return true;
  }
  return false;
}

int32_t SphElasticSolid::DockTable::findOutside(const std::vector<DockPoint>& state, uint32_t key) {
  for (size_t e = 0; e < state.size(); ++e)
    if (state[e].slot < 0 && state[e].key == key) return int32_t(e);
  return -1;
}

void SphElasticSolid::updateDocking(size_t s, Scratch& sc) {
  const uint32_t i = solid_[s];
  const size_t nn = sc.offsets.size();
  const double dt = step_dt_, d = lattice_.spacing();
  // Rates per unit time: lambda_d^q changes by Delta lambda_d^+- dt in a step of length dt (8.2.5).
  const double up = config_.docking_rate_increase, down = config_.docking_rate_decrease * dt;
  const double max_rate = config_.max_docking_rate;
  const double near2 = std::pow(config_.docking_distance * d, 2);
  const double fracture_strain = config_.fracture_strain;
  const bool can_break = !(std::isinf(fracture_strain) && fracture_strain > 0.0);  // stretch > inf: never
  const double p_break = can_break ? eventProbability(config_.fracture_rate, dt) : 0.0;
  // Lattice points at the rim of the kernel (rest weight below kMinDockingWeight W(0)) carry no force at
  // rest; a particle that reaches one from outside would dock a gap of a lattice spacing shut.
  const double min_weight = kMinDockingWeight * kernels_.poly6(0.0);
  const bool first = !dock_initialized_[i];
  std::vector<DockPoint>& state = dock_[i];  // the last evaluation's points (any order)
  // The states lie scattered in memory: fetch the next neighbourhoods' ahead (list, then its entries).
  if (s + 2 < solid_.size()) __builtin_prefetch(&dock_[solid_[s + 2]]);
  if (s + 1 < solid_.size()) {
    const std::vector<DockPoint>& next_state = dock_[solid_[s + 1]];
    const char* bytes = reinterpret_cast<const char*>(next_state.data());
    for (size_t o = 0; o < next_state.size() * sizeof(DockPoint); o += 64) __builtin_prefetch(bytes + o);
  }
  // The old points by lattice table slot (stamped, never cleared); each is taken by at most one neighbour.
  DockTable& table = sc.dock_table;
  if (table.stamps.empty()) {
    table.stamps.assign(size_t(kDockTableSize), 0u);
    table.entries.assign(size_t(kDockTableSize), -1);
  }
  if (++table.stamp == 0) {
    std::fill(table.stamps.begin(), table.stamps.end(), 0u);
    table.stamp = 1;
  }
  const size_t old_count = state.size();
  for (size_t e = old_count; e-- > 0;) {  // descending: the first of a slot wins
    const int32_t slot = state[e].slot;
    if (slot < 0) continue;
    table.stamps[size_t(slot)] = table.stamp;
    table.entries[size_t(slot)] = int32_t(e);
  }
  sc.taken.assign(old_count, 0);
  // A' = A^-1 of the nearness test, only when a free point needs it.
  Mat3 inverse;
  bool have_inverse = false;
  // The new state is written field by field into scratch that only grows (a DockPoint built on the stack
  // and copied whole stalls on store forwarding), then copied into the particle's list.
  if (sc.next.size() < nn + old_count) sc.next.resize(nn + old_count);
  DockPoint* out = sc.next.data();
  size_t out_count = 0;
  uint32_t docked = 0;
  const uint8_t* assigned = sc.assignment.assigned.data();
  const Eigen::Vector3i* indices = sc.assignment.indices.data();
  for (size_t k = 0; k < nn; ++k) {
    if (!assigned[k]) continue;
    const Eigen::Vector3i& index = indices[k];
    const uint32_t key = latticeKey(index);
    const int32_t slot = latticeTableSlot(index);
    uint8_t q_docked = 0;
    double q_rate = 0.0;
    int32_t entry = table.find(state, slot, key);
    if (entry >= 0 && slot < 0 && sc.taken[size_t(entry)]) {  // clamped key taken: the next free of it
      entry = -1;
      for (size_t e = 0; e < old_count; ++e)
        if (state[e].slot < 0 && state[e].key == key && !sc.taken[e]) {
          entry = int32_t(e);
          break;
        }
    }
    if (entry >= 0 && !sc.taken[size_t(entry)]) {
      sc.taken[size_t(entry)] = 1;
      q_docked = state[size_t(entry)].docked;
      q_rate = state[size_t(entry)].rate;
    }
    const auto isNear = [&]() {
      if (!have_inverse) {
        inverse = transform_[i].inverse();
        have_inverse = true;
      }
      return (lattice_.point(index) - inverse * sc.offsets[k]).squaredNorm() <= near2;
    };
    const auto stretch = [&]() { return sc.offsets[k].norm() / sc.rest[k].norm() - 1.0; };
    if (first) {  // the sampled lattice: every occupied point starts docked
      const bool near = isNear();
      q_docked = near ? 1 : 0;
      q_rate = near ? max_rate : 0.0;
    } else if (q_docked) {
      if (can_break && stretch() > fracture_strain &&
          uniformRandom(config_.seed, evaluations_, i, key) < p_break) {  // (8.34)
        q_docked = 0;
        q_rate = 0.0;  // a crack: it has to heal from zero
        ++detached_[s];
      } else if (q_rate != max_rate) {  // at the cap it stays there (up, dt >= 0)
        q_rate = growDockingRate(q_rate, up, max_rate, dt).rate;
      }
    } else if (isNear() && stretch() <= fracture_strain &&
               kernels_.poly6(sc.rest[k].squaredNorm()) >= min_weight &&
               dockedInnerNeighbor(state, table, index)) {
      // Occupied: docks within the step with probability 1 - exp(-integral of lambda_d^q dt) (8.34).
      const RateStep grown = growDockingRate(q_rate, up, max_rate, dt);
      q_rate = grown.rate;
      if (uniformRandom(config_.seed, evaluations_, i, key) < -std::expm1(-grown.integral)) {
        q_docked = 1;
        ++redocked_[s];
      }
    } else {
      q_rate = std::max(0.0, q_rate - down);
    }
    if (q_docked) {
      ++docked;
    } else {
      sc.assignment.assigned[k] = 0;  // free: no shape matching, no forces
    }
    if (q_docked || q_rate > 0.0) {
      DockPoint& o = out[out_count++];
      o.key = key;
      o.slot = int16_t(slot);
      o.docked = q_docked;
      o.rate = q_rate;
    }
  }
  // Lattice points without a particle: a docked one detaches, the rate decays.
  for (size_t e = 0; e < old_count; ++e) {
    if (sc.taken[e]) continue;
    const DockPoint& q = state[e];
    if (q.docked) ++separated_[s];
    const double rate = std::max(0.0, q.rate - down);
    if (rate > 0.0) {
      DockPoint& o = out[out_count++];
      o.key = q.key;
      o.slot = q.slot;
      o.docked = 0;
      o.rate = rate;
    }
  }
  state.assign(out, out + out_count);
  docked_count_[i] = docked;
  dock_initialized_[i] = 1;
}

}  // namespace rc
