// A brush type (thesis 5.4, Fig. 5.3): the skeleton's shape, its dynamics, the skin's sampling and the
// contact constants, as read from a preset in config/paint/brushes/.
#pragma once

#include <stdexcept>
#include <string>

#include "relaxed_connectivity/core/surfel_cloud.h"

namespace rc {

/// How the skeleton's active masses are integrated.
enum class BrushIntegrator {
  kVerlet,         ///< explicit Verlet (the thesis); time_step must stay below the explicit step limit
  kImplicitEuler,  ///< linearised backward Euler (one dense solve per step): stable at any time_step, damps
                   ///< the bristles' oscillation; one step per main-loop event is the fast setting
};

enum class BrushShape {
  kRound,  ///< bristle chains around the axis, a conical skin (Fig. 5.3 a, b)
  kFlat,   ///< a row of bristle chains across the width, a flat skin (Fig. 5.3 c, d)
};

/// Lengths in metres, masses in kilograms, times in seconds. The brush frame is the device's stylus frame:
/// the ferrule (where the handle points sit) in the plane z = 0, the bristles along -z, the tip at z =
/// -bristle_length.
struct BrushPreset {
  std::string name = "round";
  BrushShape shape = BrushShape::kRound;
  double bristle_length = 0.025;  ///< ferrule to tip
  double radius = 0.004;          ///< round: bristle radius at the ferrule; flat: half the width
  double thickness = 0.002;       ///< flat: ferrule thickness front to back (round: unused)
  int segments = 3;               ///< active masses along each bristle chain
  int chains = 1;                 ///< bristle chains: round 1 (on the axis) or more (on a ring); flat: across
  int handle_ring = 6;  ///< round: handle points on the ferrule ring, plus the axis and an apex in the handle
  double mass = 2e-4;   ///< per active mass
  double spring_stiffness = 40;    ///< K_s (5.1) [N/m]
  double damping = 0.01;           ///< dashpot along each spring [N s/m]
  double surfel_spacing = 5e-4;    ///< skin sampling
  double friction = 2.0;           ///< eta (5.7) [N s/m^2]
  double penalty_stiffness = 400;  ///< K_p (5.6) [N/m]
  BrushIntegrator integrator = BrushIntegrator::kVerlet;
  double time_step = 2e-4;       ///< skeleton step; for Verlet it must be below the explicit step limit
  Vec3 gravity = Vec3::Zero();   ///< [m/s^2], in the world frame
  int collision_neighbors = 10;  ///< n of (5.2)-(5.4)
  double split_angle_deg = 60;   ///< brush splitting threshold (5.4.3)
  Vec3 paint_colour = Vec3(0.8, 0.1, 0.1);  ///< wet paint the brush starts with (linear RGB, 0..1)
  double paint_volume = 1.0;                ///< wet paint volume per skin surfel (the paint model's unit)
};

class BrushPresetError : public std::runtime_error {
 public:
  explicit BrushPresetError(const std::string& message) : std::runtime_error(message) {}
};

}  // namespace rc
