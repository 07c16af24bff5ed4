// The haptic force law of thesis 5.4.1/5.4.2: at 1 kHz, from the latest contact parameters (d, N per handle
// point, handed over by the brush step at main-loop rate), the penalty K_p d N (5.6) plus the friction
// -eta d v_t (5.7), summed over the handle points in contact, and the torque about the stylus origin.
#pragma once

#include <string>
#include <vector>

#include "relaxed_connectivity/paint/device_state.h"
#include "relaxed_connectivity/paint/force_low_pass.h"

namespace rc {

/// One handle point inside the object (the content of relaxed_connectivity/HandleContact).
struct HandleContactState {
  int index = 0;                 ///< handle point of the brush preset (BrushSkeleton::handleOffsets())
  double depth = 0;              ///< d (5.2) [m], >= 0
  Vec3 normal = Vec3::UnitZ();   ///< N (5.3), unit, out of the object, device base frame
  Vec3 position = Vec3::Zero();  ///< the handle point where d was evaluated, device base frame
};

/// The content of relaxed_connectivity/BrushContact.
struct ContactParameters {
  double penalty_stiffness = 0;  ///< K_p [N/m]
  double friction = 0;           ///< eta [N s/m^2]
  std::vector<HandleContactState> handles;
  Vec3 bristle_force = Vec3::Zero();  ///< [N], device base frame
};

/// Why contact parameters are refused (kNone: accepted).
enum class ContactProblem {
  kNone,
  kNonFinite,
  kNegativeConstant,
  kNegativeDepth,
  kNonUnitNormal,
  kUnknownHandle,
  kDuplicateHandle
};
const char* contactProblemName(ContactProblem problem);

enum class DepthMode {
  kConstant,  ///< the thesis: the latest d until the next update
  kPlane,     ///< d extrapolated along N: d0 - (x - x0).N, clamped at 0 (equals d0 at the update instant)
};
/// "constant" / "plane"; throws std::invalid_argument otherwise.
DepthMode parseDepthMode(const std::string& name);

struct HapticForceLawOptions {
  DepthMode depth_mode = DepthMode::kPlane;
  double stale_timeout = 0.1;  ///< [s] contact parameters older than this fade out ...
  double fade_time = 0.05;     ///< [s] ... linearly to zero over this time
  bool add_bristle_force =
      true;  ///< add the bristles' spring force on the handle (all forces on handle points)
  double normal_tolerance = 1e-3;  ///< | |N| - 1 | accepted

  /// Throws std::invalid_argument naming the bad option.
  void validate() const;
};

/// What the law gives for one instant.
struct HapticForce {
  Wrench wrench =
      Wrench::Zero();  ///< force [N] (0..2) and torque about the stylus origin [N m] (3..5), base frame
  int handles_in_contact = 0;  ///< with d > 0 after extrapolation
  double fade = 0;             ///< 1: fresh contact, 0: faded out (or no contact yet)
};

class HapticForceLaw {
 public:
  /// `handle_offsets`: the handle points in the stylus frame (BrushSkeleton::handleOffsets()).
  HapticForceLaw(std::vector<Vec3> handle_offsets, HapticForceLawOptions options);

  /// Checks contact parameters before setContact.
  ContactProblem check(const ContactParameters& contact) const;
  /// Takes checked contact parameters evaluated at time `t` [s, the evaluate() clock]. Copying into storage
  /// reserved for every handle point: no allocation.
  void setContact(const ContactParameters& contact, double t);
  void clearContact() { has_contact_ = false; }

  /// The force at time `now` for the device state `device`.
  HapticForce evaluate(const DeviceState& device, double now) const;
  /// 1 up to stale_timeout after the contact update, then linearly down to 0 over fade_time.
  double fade(double now) const;
  /// Age of the contact parameters at `now` (infinite when there are none).
  double contactAge(double now) const;

  int handleCount() const { return int(offsets_.size()); }
  const HapticForceLawOptions& options() const { return options_; }

 private:
  std::vector<Vec3> offsets_;
  HapticForceLawOptions options_;
  ContactParameters contact_;
  double contact_time_ = 0;
  bool has_contact_ = false;
};

}  // namespace rc
