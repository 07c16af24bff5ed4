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
  if (!(options_.time_step > 0) || !std::isfinite(options_.time_step))
    throw std::invalid_argument("PaintDiffusion: time_step must be positive");
  tree_ = std::make_unique<KdTree>(positions_);
  neighbours_.resize(positions_.size());
  area_.assign(positions_.size(), NAN);
  kappa_.assign(positions_.size(), NAN);
  in_list_.assign(positions_.size(), 0);
  sweep_pos_.assign(positions_.size(), kNotInSweep);
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

const std::vector<std::pair<uint32_t, double>>& PaintDiffusion::neighbours(uint32_t i) {
  std::vector<std::pair<uint32_t, double>>& list = neighbours_[i];
  if (!std::isnan(area_[i])) return list;
  const double r = options_.neighbour_radius;
  tree_->radius(positions_[i], r, found_, true);
  // The sampling density (surfels per area, i itself included) with the kernel normalised to a unit
  // integral over the plane: 2 pi int_0^R (1 - r/R)^2 r dr = pi R^2 / 6.
  double density = 0;
  for (const Neighbor& n : found_) {
    const double k = std::pow(1.0 - std::sqrt(n.sq_dist) / r, 2);
    density += k;
    if (n.index != i && n.sq_dist > 0) list.push_back({n.index, k});
  }
  area_[i] = M_PI * r * r / 6.0 / std::max(density, 1.0);
  return list;
}

double PaintDiffusion::area(uint32_t i) {
  neighbours(i);
  return area_[i];
}

double PaintDiffusion::kappa(uint32_t i) {
  if (!std::isnan(kappa_[i])) return kappa_[i];
  double moment = 0;  // sum_j k_ij A_j |d_ij|^2
  for (const auto& [j, k] : neighbours(i))
    moment += k * area(j) * (positions_[j] - positions_[i]).squaredNorm();
  kappa_[i] = moment > 0 ? 4.0 / moment : 0.0;
  return kappa_[i];
}

void PaintDiffusion::visit(uint32_t i, std::vector<PaintState>& paint) {
  const double dt = options_.time_step, a_i = area(i), kappa_i = kappa(i);
  for (const auto& [j, k] : neighbours(i)) {
    if (sweep_pos_[j] < sweep_pos_[i]) continue;  // the pair was exchanged when j was visited
    const double a_j = area(j);
    const double c_i = paint[i].wet_volume / a_i, c_j = paint[j].wet_volume / a_j;
    if (c_i == c_j) continue;
    const double rate = options_.diffusion * 0.5 * (kappa_i + kappa(j)) * k * (a_i + a_j);
    const double moved = -std::expm1(-rate * dt) * (c_i - c_j) * a_i * a_j / (a_i + a_j);  // (5.15)
    if (moved == 0) continue;
    PaintState& giver = moved > 0 ? paint[i] : paint[j];
    PaintState& taker = moved > 0 ? paint[j] : paint[i];
    const double v = std::abs(moved);
    giver.wet_volume -= v;
    addWetPaint(taker, giver, v);  // (5.11)
    if (moved > 0) markWet(j);
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
      // The surfels wet at the start (those that get wet now join the next sweep), in ascending and
      // descending index order in turn.
      sweep_ = wet_;
      std::sort(sweep_.begin(), sweep_.end());
      if (sweeps_ % 2 == 1) std::reverse(sweep_.begin(), sweep_.end());
      for (size_t k = 0; k < sweep_.size(); ++k) sweep_pos_[sweep_[k]] = uint32_t(k);
      cursor_ = 0;
      sweeping_ = true;
    }
    visit(sweep_[cursor_++], paint);
    ++visits;
    if (cursor_ == sweep_.size()) {
      for (uint32_t i : sweep_) sweep_pos_[i] = kNotInSweep;
      sweeping_ = false;
      ++sweeps_;
    }
  }
  return visits;
}

}  // namespace rc
