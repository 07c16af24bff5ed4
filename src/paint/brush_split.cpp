#include "relaxed_connectivity/paint/brush_split.h"

#include <cmath>
#include <stdexcept>

namespace rc {

BrushSplit splitBrush(const std::vector<int>& actives, const std::vector<Vec3>& normals,
                      double threshold_deg) {
  if (actives.size() != normals.size()) throw std::invalid_argument("splitBrush: one normal per active mass");
  BrushSplit out;
  if (actives.empty()) return out;
  const double cos_threshold = std::cos(threshold_deg * M_PI / 180.0);
  // Seeds: start with the first mass, add the mass least aligned with every seed while it is beyond the
  // threshold from all of them.
  std::vector<size_t> seeds{0};
  for (;;) {
    size_t farthest = 0;
    double worst = 2;  // max over seeds of the cosine, minimised over masses
    for (size_t i = 0; i < actives.size(); ++i) {
      double best = -2;
      for (size_t s : seeds) best = std::max(best, normals[i].dot(normals[s]));
      if (best < worst) worst = best, farthest = i;
    }
    if (worst >= cos_threshold) break;
    seeds.push_back(farthest);
  }
  out.split = seeds.size() > 1;
  out.tips.resize(seeds.size());
  std::vector<Vec3> sums(seeds.size(), Vec3::Zero());
  for (size_t i = 0; i < actives.size(); ++i) {
    size_t tip = 0;
    for (size_t s = 1; s < seeds.size(); ++s)
      if (normals[i].dot(normals[seeds[s]]) > normals[i].dot(normals[seeds[tip]])) tip = s;
    out.tips[tip].push_back(actives[i]);
    sums[tip] += normals[i];
  }
  for (const Vec3& s : sums) out.tip_normals.push_back(s.norm() > 0 ? Vec3(s.normalized()) : s);
  return out;
}

}  // namespace rc
