// Surfel classes of thesis 4.1.2 (Fig. 4.4): surface, edge and outside surfels of a CSG scene.
#pragma once

#include <cstdint>
#include <vector>

#include "relaxed_connectivity/render/csg/clip_partners.h"
#include "relaxed_connectivity/render/csg/clip_surfel_discs.h"
#include "relaxed_connectivity/render/csg/csg_tree.h"

namespace rc {

/// For a surfel s of patch C (Fig. 4.4). The patches of s's clipping partners VARY over the disc of s; every
/// other patch does not intersect s, so s lies entirely inside or entirely outside it, and the classification
/// of the centre c_s against that patch holds for the whole disc (the argument of 4.2.2 for "unknown"). This
/// constant classification uses the two surfels of the patch nearest to c_s over the WHOLE cloud (4.4; one
/// surfel: (4.3); empty patch: unknown). Patches made only of texture-discontinuity surfels (role 2) count as
/// unknown: they clip colour, never geometry (4.3). Then
///  - outside: Algorithm 4.2 at c_s returns false for EVERY true/false assignment of the varying patches:
///             no point of s is on the CSG surface, s is discarded. Without partners this is the thesis'
///             "c_s not in S_{A o B} and s does not intersect S_B"; with partners it applies the same rule to
///             nested operations (an edge surfel of C touching only the part of A that lies outside B in
///             (A & B) & C is discarded, as the thesis' operation-by-operation classification would);
///  - edge:    s has partners (its disc intersects a disc of another patch) and is not outside: its fragments
///             are clipped per pixel (4.2.2);
///  - surface: no partners and not outside: splatted normally.
/// More than 12 distinct varying patches: edge (not enumerated).
enum class SurfelClass : uint8_t { kSurface = 0, kEdge = 1, kOutside = 2 };

/// `tree` must be normalised and contain every patch of `discs`.
std::vector<SurfelClass> classifySurfels(const SurfelDiscs& discs, const ClipPartners& partners,
                                         const CsgTree& tree);

}  // namespace rc
