#include "relaxed_connectivity/paint/paint_diffusion.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace rc {

PaintDiffusion::PaintDiffusion(const std::vector<Vec3>& positions, PaintDiffusionOptions options)
    : positions_(positions), options_(options) {
  if (!(options_.diffusion >= 0) || !std::isfinite(options_.diffusion))
    throw std::invalid_argument("PaintDiffusion: diffusion must be >= 0");
  if (options_.diffusion > 0 && !(options_.neighbour_radius > 0))
    throw std::invalid_argument("PaintDiffusion: neighbour_radius must be positive");
  if (!(options_.time_step > 0) || !(options_.max_exchange > 0 && options_.max_exchange <= 0.5))
    throw std::invalid_argument("PaintDiffusion: time_step must be positive and max_exchange in (0, 0.5]");
  tree_ = std::make_unique<KdTree>(positions_);
  coefficients_.resize(positions_.size());
  in_list_.assign(positions_.size(), 0);
  in_sweep_.assign(positions_.size(), 0);
}

PaintDiffusion::~PaintDiffusion() = default;

void PaintDiffusion::markWet(size_t surfel) {
  if (surfel >= positions_.size())
    throw std::out_of_range("PaintDiffusion::markWet: surfel " + std::to_string(surfel) + " of " +
                            std::to_string(positions_.size()));
  if (in_list_[surfel]) return;
  in_list_[surfel] = 1;
  wet_.push_back(uint32_t(surfel));
}

const std::vector<std::pair<uint32_t, double>>& PaintDiffusion::coefficients(uint32_t i) {
  std::vector<std::pair<uint32_t, double>>& c = coefficients_[i];
  if (!c.empty()) return c;
  const double r = options_.neighbour_radius;
  tree_->radius(positions_[i], r, found_, true);
  double moment = 0;
  for (const Neighbor& n : found_) {
    if (n.index == i || n.sq_dist <= 0) continue;
    const double k = std::pow(1.0 - std::sqrt(n.sq_dist) / r, 2);
    c.push_back({n.index, k});
    moment += k * n.sq_dist;
  }
  // c_ij per second: 4 D k_ij / sum_j k_ij d_ij^2 (second moment matched to (5.14) on a surface).
  for (auto& [j, k] : c) k *= 4 * options_.diffusion / moment;
  return c;
}

void PaintDiffusion::visit(uint32_t i, std::vector<PaintState>& paint) {
  const std::vector<std::pair<uint32_t, double>>& c = coefficients(i);
  const double dt = options_.time_step;
  double total = 0;
  for (const auto& [j, rate] : c) total += (in_sweep_[j] ? 0.5 : 1.0) * rate * dt;
  // Sub-visits keep every exchange below max_exchange of the difference (explicit stability).
  const int parts = std::max(1, int(std::ceil(total / options_.max_exchange)));
  for (int part = 0; part < parts; ++part) {
    for (const auto& [j, rate] : c) {
      PaintState& a = paint[i];
      PaintState& b = paint[j];
      // Both wet at the sweep's start: each side's visit moves half (the 1/2 of (5.15)).
      const double share = (in_sweep_[j] ? 0.5 : 1.0) * rate * dt / parts;
      const double moved = share * (a.wet_volume - b.wet_volume);
      if (moved == 0) continue;
      PaintState& giver = moved > 0 ? a : b;
      PaintState& taker = moved > 0 ? b : a;
      const double v = std::abs(moved);
      giver.wet_volume -= v;
      addWetPaint(taker, giver, v);  // (5.11)
      if (moved > 0) markWet(j);
    }
  }
}

size_t PaintDiffusion::run(std::vector<PaintState>& paint, size_t max_visits) {
  if (paint.size() != positions_.size())
    throw std::invalid_argument("PaintDiffusion::run: " + std::to_string(paint.size()) +
                                " paint states for " + std::to_string(positions_.size()) + " surfels");
  if (options_.diffusion == 0) return 0;
  size_t visits = 0;
  while (visits < max_visits) {
    if (!sweeping_) {
      if (pending_time_ < options_.time_step * (1 - 1e-9) || wet_.empty()) break;  // rounding of sums
      pending_time_ -= options_.time_step;
      // Surfels without wet paint (dried, or given everything away) leave the list.
      wet_.erase(std::remove_if(wet_.begin(), wet_.end(),
                                [&](uint32_t i) { return paint[i].wet_volume <= 0 && !(in_list_[i] = 0); }),
                 wet_.end());
      if (wet_.empty()) break;
      sweep_ = wet_;  // the surfels wet at the start; those that get wet now join the next sweep
      for (uint32_t i : sweep_) in_sweep_[i] = 1;
      cursor_ = 0;
      sweeping_ = true;
    }
    visit(sweep_[cursor_++], paint);
    ++visits;
    if (cursor_ == sweep_.size()) {
      for (uint32_t i : sweep_) in_sweep_[i] = 0;
      sweeping_ = false;
      ++sweeps_;
    }
  }
  return visits;
}

}  // namespace rc
