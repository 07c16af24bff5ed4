// Texture patches per mesh triangle (thesis 6.2): the surfels near a triangle are EWA-splatted (src/render's
// set-up and rasterizer) in an orthographic view onto the triangle's plane, its longest edge along the image
// x-axis, with visibility splatting; the patch resolution is refined until the area-weighted error (6.1)
// between the surfels and the bilinearly interpolated texture drops below a threshold, or the texel spacing
// reaches d_min / (2 sqrt 2), d_min the smallest distance between two of the patch's surfels. Colour and
// normal textures (6.2), and optionally depth textures (the surfels' heights above the triangle, for
// displacement mapping), are refined separately; all are then rendered at the finest of their resolutions so
// that they share one atlas layout (the thesis keeps their sizes apart, which needs more sets of texture
// coordinates than OBJ has). Each patch is the packing mask's raster (atlas_packing.h): the triangle plus a
// border, so bilinear filtering never reads a neighbour.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "relaxed_connectivity/convert/atlas_packing.h"
#include "relaxed_connectivity/convert/stage_progress.h"
#include "relaxed_connectivity/core/triangle_mesh.h"

namespace rc {

/// Which texture a patch holds.
enum class TextureKind { kColor, kNormal, kDepth };

struct TextureOptions {
  /// Colour threshold: (6.1) divided by the area of the patch's surfels, i.e. the area-weighted mean RGB
  /// distance (L2, channels in [0, 1]) between a surfel and the texture at its centre.
  double color_error = 0.03;
  /// Normal threshold: the area-weighted mean of (6.2), 1 - N_s . N_t.
  double normal_error = 0.002;
  bool normal_texture = true;
  /// Depth threshold: the area-weighted mean |h_s - h_t| of a surfel's height above the triangle's plane and
  /// the texture's, over the median surfel radius (scale-free, like the others).
  double depth_error = 0.05;
  bool depth_texture = false;
  /// Texels along the base at the first refinement step, and the factor the resolution grows by per step.
  double start_base_texels = 2;
  double refinement_factor = 1.41421356237;
  /// Never more texels along a base than this (a guard for duplicate surfels, whose d_min is 0).
  double max_base_texels = 512;
  /// Texels around each triangle (atlas_packing.h: a patch claims its triangle plus this border); must be the
  /// atlas' border (convertSurfels takes it from AtlasOptions).
  int border = 1;
  /// Surfels farther than this from a triangle's plane are not splatted into its patch [m]; 0: the larger of
  /// four times the median surfel radius and 1 % of the bounding box diagonal.
  double projection_depth = 0;
  int threads = 0;  ///< 0: all cores
};

/// A triangle's frame: the base from `origin` along `x_axis` (the longest edge), the apex on the +y side,
/// `normal` = the triangle's (right-handed with its corner order). corner[k]: the mesh corner (0, 1, 2 of the
/// triangle) at the base start, base end and apex.
struct PatchFrame {
  Eigen::Vector3d origin, x_axis, y_axis, normal;
  std::array<int, 3> corner;
  double base = 0, apex_x = 0, height = 0;  ///< [m]
};
PatchFrame patchFrame(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c);

/// One texture of one triangle: the packing mask's raster of `shape` (texel (x, y) centred at (x + 0.5,
/// y + 0.5) - origin texels from the base start along the frame's x and y axes), row 0 at the base.
struct TexturePatch {
  PatchShape shape;
  double texels_per_unit = 0;
  /// The resolution this texture's own refinement chose; texels_per_unit is the finer of the colour's and the
  /// normal's, so that both textures share one layout (one set of texture coordinates, as OBJ requires).
  double refined_texels_per_unit = 0;
  int width = 0, height = 0;
  double origin = 0;
  /// RGB in [0, 1], unit normals in the world frame, or (depth) x: the height above the triangle's plane
  /// along its normal [m], y = z = 0.
  std::vector<Eigen::Vector3f> texels;
  double error = 0;                  ///< the area-weighted mean error the refinement ended with
  bool at_resolution_limit = false;  ///< stopped by the texel spacing limit, not by the threshold
  int steps = 0;                     ///< refinement steps taken
  uint32_t surfels = 0;              ///< |P_t|: visible surfels with centres on the patch
  uint32_t filled_texels = 0;        ///< texels no splat covered, filled from their neighbours
};

struct TrianglePatches {
  PatchFrame frame;
  TexturePatch color, normal, depth;  ///< normal, depth: empty without normal_texture, depth_texture
};

struct TextureStats {
  size_t triangles = 0;
  size_t texels = 0;  ///< of each texture (colour, normal, depth: one layout)
  /// Texels the colour and the normal refinement asked for on their own (the thesis' separate sizes).
  size_t color_refined_texels = 0, normal_refined_texels = 0, depth_refined_texels = 0;
  double depth_unit = 0;           ///< the median surfel radius the depth error is measured in [m]
  size_t at_resolution_limit = 0;  ///< colour patches stopped by the spacing limit
  size_t empty_patches = 0;        ///< triangles no surfel reached (filled with the nearest surfel's colour)
  double projection_depth = 0;     ///< [m], as used
  double seconds = 0;
};

/// Texture patches for every triangle of `mesh` from `surfels` (positions, normals, radii or axes; colours
/// optional: white without). `progress` is called now and then from one thread with the fraction of the
/// triangles done; returning false throws ConversionCancelled once the triangles in flight are done. Throws
/// std::invalid_argument for surfels without normals or radii, non-finite input, a degenerate triangle
/// (named by index), or bad options.
std::vector<TrianglePatches> computeTexturePatches(const TriangleMesh& mesh, const SurfelCloud& surfels,
                                                   const TextureOptions& options = {},
                                                   TextureStats* stats = nullptr,
                                                   const StageProgress& progress = nullptr);

/// Bilinear interpolation of a width x height grid of texels at continuous coordinates (x, y), texel (i, j)
/// centred at (i + 0.5, j + 0.5), clamped to the grid; at(i, j) returns texel (i, j) as an Eigen::Vector3f.
template <class At>
Eigen::Vector3f bilinear(int width, int height, double x, double y, At&& at) {
  const double fx = std::clamp(x - 0.5, 0.0, double(width - 1));
  const double fy = std::clamp(y - 0.5, 0.0, double(height - 1));
  const int x0 = std::min(int(fx), width - 1), y0 = std::min(int(fy), height - 1);
  const int x1 = std::min(x0 + 1, width - 1), y1 = std::min(y0 + 1, height - 1);
  const float tx = float(fx - x0), ty = float(fy - y0);
  const Eigen::Vector3f a = at(x0, y0), b = at(x1, y0), c = at(x0, y1), d = at(x1, y1);
  return (1 - ty) * ((1 - tx) * a + tx * b) + ty * ((1 - tx) * c + tx * d);
}

/// The texture's bilinear interpolation at continuous raster coordinates (texel centres at i + 0.5),
/// clamped to the raster.
Eigen::Vector3f sampleBilinear(const TexturePatch& patch, double x, double y);

/// A point of the triangle (world frame) in the patch's raster coordinates.
Eigen::Vector2d rasterCoordinates(const TexturePatch& patch, const PatchFrame& frame,
                                  const Eigen::Vector3d& p);

}  // namespace rc
