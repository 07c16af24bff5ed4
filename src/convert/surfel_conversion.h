// Point cloud -> textured mesh (thesis 6), all stages in one call: reconstruction and Garland-Heckbert
// simplification (6.1), the geometric error of the result, error-bounded texture patches (6.2) and their
// atlas (6.3). The two parameters the thesis names are the simplification bound and the texture threshold.
#pragma once

#include <functional>
#include <string>

#include "relaxed_connectivity/convert/geometric_error.h"
#include "relaxed_connectivity/convert/mesh_simplification.h"
#include "relaxed_connectivity/convert/surface_reconstruction.h"
#include "relaxed_connectivity/convert/textured_mesh.h"

namespace rc {

struct ConversionOptions {
  ReconstructionOptions reconstruction;
  SimplificationOptions simplification;  ///< default: max_error 0.0005 of the bounding box diagonal
  TextureOptions texture;                ///< (its border is taken from atlas.border)
  AtlasOptions atlas;
  bool measure_geometric_error = true;
  ConversionOptions() { simplification.max_error = 0.0005; }
};

/// The stages in order, as named in progress reports and results.
enum class ConversionStage { kReconstruction, kSimplification, kGeometricError, kTextures, kPacking };
const char* stageName(ConversionStage stage);

struct ConversionResult {
  TexturedMesh textured;
  ReconstructionStats reconstruction;
  SimplificationStats simplification;
  GeometricError geometric_error;  ///< zero unless measured
  TextureStats texture;
  size_t radii_estimated = 0;  ///< surfels that came without radii (estimated, 3.3)
  /// Texture errors over the triangles: the largest and the area-weighted mean of the colour error (6.1)
  /// and of the normal error (6.2) the patches ended with, and of the depth error
  /// (TextureOptions::depth_error).
  double color_error_max = 0, color_error_mean = 0, normal_error_max = 0, normal_error_mean = 0;
  double depth_error_max = 0, depth_error_mean = 0;
  double seconds[5] = {0, 0, 0, 0, 0};  ///< per ConversionStage
  double totalSeconds() const;
};

/// progress(stage, fraction): called at each stage's start and end and now and then inside; return false to
/// cancel (ConversionCancelled is thrown from the stage).
using ConversionProgress = std::function<bool(ConversionStage stage, double fraction)>;

/// Converts oriented surfels (normals required; radii estimated when absent; colours optional). Throws
/// std::invalid_argument for bad input (named by each stage), std::runtime_error without CGAL, and
/// ConversionCancelled.
ConversionResult convertSurfels(const SurfelCloud& surfels, const ConversionOptions& options = {},
                                const ConversionProgress& progress = nullptr);

}  // namespace rc
