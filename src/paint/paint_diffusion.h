// Surface diffusion of wet paint (thesis 5.6.2): a background process that visits the surfels holding wet
// paint and exchanges volume with their neighbours, mixing colours as in (5.11), so that a watercolour
// stroke bleeds. Bounded work per call keeps the main loop interactive.
#pragma once

#include <memory>
#include <vector>

#include "relaxed_connectivity/core/kd_tree.h"
#include "relaxed_connectivity/paint/paint_state.h"

namespace rc {

struct PaintDiffusionOptions {
  double diffusion = 0;         ///< isotropic D [m^2/s] of (5.14); 0 switches diffusion off
  double neighbour_radius = 0;  ///< exchange partners within this distance [m] (a few surfel spacings)
  double time_step = 0.05;      ///< simulated time of one sweep over the wet surfels [s]
};

/// Reading of (5.15). As printed, dV_ij = 1/2 (V_i - V_j) exp(-1 / (D_ij dt)) with D_ij = d^T D d would grow
/// with distance, against the text ("exponential decay with distance"), and its dimensions do not match.
/// This class solves the diffusion equation (5.14) for the paint per area c = V / A, A_i the area surfel i
/// stands for (from the sampling density around it, so that children at the paint buffer's resolution and
/// originals mix correctly). Pairs within R exchange with a kernel k_ij = (1 - |x_j - x_i| / R)^2 scaled per
/// surfel so that its area-weighted second moment is that of (5.14) (sum_j kappa_i k_ij A_j |d_ij|^2 = 4),
/// K_ij = (kappa_i + kappa_j) k_ij / 2 (symmetric: volume is conserved exactly), and each pair moves the
/// exact two-surfel solution over the time step,
///   m_ij = (1 - exp(-D K_ij (A_i + A_j) dt)) (c_i - c_j) A_i A_j / (A_i + A_j),
/// so no exchange overshoots at any step (for equal areas, 1/2 (V_i - V_j) times a decay factor: the 1/2 and
/// the exponential of (5.15)). Every pair is exchanged once per sweep, the sweeps visiting the wet surfels in
/// ascending and descending order in turn (one order alone drifts the paint along it).
class PaintDiffusion {
 public:
  /// `positions`: the surfels (not copied: must outlive this object and not change while it is used).
  PaintDiffusion(const std::vector<Vec3>& positions, PaintDiffusionOptions options);
  ~PaintDiffusion();

  /// A surfel received wet paint: it joins the wet list (from the next sweep on).
  void markWet(size_t surfel);
  /// Simulated time to diffuse; whole sweeps of time_step are run as run() is called.
  void addTime(double seconds) { pending_time_ += seconds; }
  double pendingTime() const { return pending_time_; }

  /// Visits up to `max_visits` wet surfels of the pending sweeps (continuing where the last call stopped),
  /// updating `paint` (indexed like the positions). Returns the visits done: 0 when no whole sweep is
  /// pending or diffusion is off. The result depends only on the sequence of visits, not on how the calls
  /// split it.
  size_t run(std::vector<PaintState>& paint, size_t max_visits);

  size_t wetCount() const { return wet_.size(); }
  size_t sweepsDone() const { return sweeps_; }

 private:
  void visit(uint32_t i, std::vector<PaintState>& paint);
  /// Neighbours (j, k_ij) of surfel i, its area A_i and second-moment scale kappa_i (computed on first use).
  const std::vector<std::pair<uint32_t, double>>& neighbours(uint32_t i);
  double area(uint32_t i);
  double kappa(uint32_t i);

  const std::vector<Vec3>& positions_;
  PaintDiffusionOptions options_;
  std::unique_ptr<KdTree> tree_;
  std::vector<std::vector<std::pair<uint32_t, double>>> neighbours_;  // per surfel, lazily: (j, k_ij)
  std::vector<double> area_, kappa_;                                  // lazily (NaN: not yet)
  std::vector<uint8_t> in_list_;
  std::vector<uint32_t> sweep_pos_;    // position in the current sweep (kNotInSweep otherwise)
  std::vector<uint32_t> wet_, sweep_;  // the wet list; the snapshot the current sweep visits
  size_t cursor_ = 0;                  // next position in sweep_
  bool sweeping_ = false;
  double pending_time_ = 0;
  size_t sweeps_ = 0;
  std::vector<Neighbor> found_;
  static constexpr uint32_t kNotInSweep = UINT32_MAX;
};

}  // namespace rc
