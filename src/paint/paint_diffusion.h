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
  double max_exchange = 0.25;   ///< largest share of its excess a surfel gives per sub-visit (stability)
};

/// Reading of (5.15). As printed, dV_ij = 1/2 (V_i - V_j) exp(-1 / (D_ij dt)) with D_ij = d^T D d would grow
/// with distance, against the text ("exponential decay with distance"), and its dimensions do not match.
/// This class exchanges dV_ij = c_ij (V_i - V_j) with c_ij = 4 D dt k_ij / sum_j k_ij |x_j - x_i|^2 and a
/// kernel k_ij = (1 - |x_j - x_i| / R)^2 within R: the second moment of the neighbourhood weights is matched
/// to (5.14), so a deposit on a plane spreads with variance 2 D t per axis, as the diffusion equation says,
/// and volume is conserved exactly (every exchange moves paint from one surfel to another). A pair whose
/// both surfels are wet is visited from both sides with half the coefficient each (the 1/2 of (5.15)).
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
  const std::vector<std::pair<uint32_t, double>>& coefficients(uint32_t i);

  const std::vector<Vec3>& positions_;
  PaintDiffusionOptions options_;
  std::unique_ptr<KdTree> tree_;
  std::vector<std::vector<std::pair<uint32_t, double>>> coefficients_;  // per surfel, lazily: (j, c_ij / dt)
  std::vector<uint8_t> in_list_, in_sweep_;
  std::vector<uint32_t> wet_, sweep_;  // the wet list; the snapshot the current sweep visits
  size_t cursor_ = 0;                  // next position in sweep_
  bool sweeping_ = false;
  double pending_time_ = 0;
  size_t sweeps_ = 0;
  std::vector<Neighbor> found_;
};

}  // namespace rc
