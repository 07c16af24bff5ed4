// The paint at one surfel or brush sample (thesis 5.6): wet and dry paint, each with a "colour" that is a set
// of appearance attributes (RGB, reflectivity, shininess), the wet and dry volumes and the optical density.
#pragma once

#include "relaxed_connectivity/core/surfel_cloud.h"

namespace rc {

/// A paint "colour" in the thesis' sense (5.6): everything that determines appearance and mixes by volume.
struct PaintColour {
  Vec3 rgb = Vec3::Zero();  ///< linear RGB, 0..1
  double reflectivity = 0;  ///< environment reflection weight, 0..1 (metallic paint)
  double shininess = 0;     ///< specular exponent

  /// Volume-weighted mix: (a va + b vb) / (va + vb); `a` when both volumes are zero.
  static PaintColour mix(const PaintColour& a, double va, const PaintColour& b, double vb);
  bool operator==(const PaintColour& o) const {
    return rgb == o.rgb && reflectivity == o.reflectivity && shininess == o.shininess;
  }
};

struct PaintState {
  PaintColour wet;             ///< C_w
  PaintColour dry;             ///< C_d (the object's own colour before any paint dried on it)
  double wet_volume = 0;       ///< V_w
  double dry_volume = 0;       ///< V_d
  double optical_density = 1;  ///< rho of the wet paint: alpha = min(rho V_w, 1)
  /// tau of (5.9)/(5.10) with which wet paint leaves this surfel [1/(pressure s)]; a property of the surfel
  /// (its side: the brush, or a region of the object that holds its paint, tau = 0), not of the paint, so
  /// it does not mix. Negative: not set, the paint type's rate for the side applies.
  double transfer_rate = -1;

  bool operator==(const PaintState& o) const {
    return wet == o.wet && dry == o.dry && wet_volume == o.wet_volume && dry_volume == o.dry_volume &&
           optical_density == o.optical_density && transfer_rate == o.transfer_rate;
  }
};

/// Adds `volume` of the wet paint of `from` to `into` (5.11): the wet colour and the optical density become
/// the volume-weighted means of what `into` held and what it received (unchanged when both volumes are 0).
void addWetPaint(PaintState& into, const PaintState& from, double volume);

/// The visible colour (5.8): alpha C_w + (1 - alpha) C_d with alpha = min(rho V_w, 1) (dry paint is opaque).
PaintColour visibleColour(const PaintState& s);
/// A colour channel 0..1 as the 8-bit value a viewer gets.
uint8_t colourByte(double channel);
/// Whether a viewer sees `a` and `b` alike: the same 8-bit visible colour and visible reflectivity in the
/// same 1/255 step (it weighs an environment colour of 8-bit channels: within a step a pixel moves by less
/// than a level). Drying under opaque wet paint, for one, is unseen.
bool lookAlike(const PaintState& a, const PaintState& b);

}  // namespace rc
