#include "relaxed_connectivity/core/weight_function.h"

namespace rc {

WeightKind parseWeightKind(const std::string& name) {
  if (name == "gaussian") return WeightKind::kGaussian;
  if (name == "clipped_gaussian") return WeightKind::kClippedGaussian;
  if (name == "wendland" || name == "wendland_c2") return WeightKind::kWendlandC2;
  throw std::invalid_argument("unknown weight function '" + name +
                              "' (expected gaussian, clipped_gaussian or wendland)");
}

const char* weightKindName(WeightKind kind) {
  switch (kind) {
    case WeightKind::kGaussian:
      return "gaussian";
    case WeightKind::kClippedGaussian:
      return "clipped_gaussian";
    case WeightKind::kWendlandC2:
      return "wendland";
  }
  return "?";
}

}  // namespace rc
