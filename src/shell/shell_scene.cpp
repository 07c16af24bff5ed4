#include "relaxed_connectivity/shell/shell_scene.h"

#include <cmath>

namespace rc {

double ShellSceneBalloon::pressureAt(double t) const {
  if (!enabled) return 0.0;
  if (ramp_time <= 0.0 || t >= ramp_time) return pressure;
  return start_pressure + (pressure - start_pressure) * t / ramp_time;
}

double ShellSceneBalloon::pressureAt(double t, double tear_time) const {
  if (vent_time <= 0.0 || tear_time < 0.0 || t <= tear_time) return pressureAt(t);
  return pressureAt(tear_time) * std::exp(-(t - tear_time) / vent_time);
}

}  // namespace rc
