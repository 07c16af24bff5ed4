// setupCircularEwaSplat for four surfels at a time (AVX2 in double precision, perspective cameras): the same
// operations in the same order, so the records are bitwise those of the scalar set-up. Lanes outside the
// common case (edge-on, the plane depth undefined over the box) are set up by setupCircularEwaSplat.
#pragma once

#include "relaxed_connectivity/render/splat/ewa_splat.h"

namespace rc {

/// True if this build has the four-wide set-up and the CPU executes AVX2.
bool circularSetupAvx2Available();

/// Sets up surfels k = 0..3 (centres, normals of any positive length, radii) as setupCircularEwaSplat
/// would for a perspective camera: rasters[k], unit_normals[k] and results[k].
void setupCircularEwaSplats4(const Vec3* centers, const Vec3* normals, const double* radii,
                             const CameraFrame& camera, const EwaParams& params, SplatRaster rasters[4],
                             float unit_normals[4][3], SplatSetup results[4]);

/// The first test of the set-up alone, four surfels at a time: writes to `kept` the indices (0..count) of the
/// surfels that setupCircularEwaSplat would not cull at once (near/far clip, back-face with
/// params.backface_culling), with the same arithmetic, and of every surfel with invalid input (its set-up
/// says why); returns how many. The others are culled: their full set-up is skipped.
size_t unculledCircularSurfels(const Vec3* centers, const Vec3* normals, const double* radii, size_t count,
                               const CameraFrame& camera, const EwaParams& params, uint32_t* kept);

}  // namespace rc
