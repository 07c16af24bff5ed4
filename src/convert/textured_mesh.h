// A triangle mesh with its texture atlas (thesis 6.3): the triangles' colour and normal patches packed by
// Algorithm 6.1 into pages, with per-corner texture coordinates, per-triangle tangent frames for the normal
// map, and per-vertex colours as a fallback for tools that ignore textures.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <vector>

#include "relaxed_connectivity/convert/atlas_packing.h"
#include "relaxed_connectivity/convert/texture_patches.h"
#include "relaxed_connectivity/core/triangle_mesh.h"

namespace rc {

struct TexturePage {
  uint32_t width = 0, height = 0;
  std::vector<Rgba> color;   ///< row-major, top row first
  std::vector<Rgba> normal;  ///< tangent-space normal map (empty without normal textures)
  /// Displacement: per texel the surface's height above its triangle's plane along the face normal [m]
  /// (empty without depth textures; 0 where no patch claims the texel).
  std::vector<float> depth;
  /// Per texel, the triangle whose patch claims it (-1: none); then per mip level (AtlasOptions::mip_levels)
  /// the same at (width >> k) x (height >> k) (rounded up), with the level's colour and normal images.
  std::vector<int32_t> owner;
  struct Mip {
    uint32_t width = 0, height = 0;
    std::vector<Rgba> color, normal;
    std::vector<float> depth;
    std::vector<int32_t> owner;
  };
  std::vector<Mip> mips;  ///< level 1, 2, ...
};

struct TexturedMesh {
  /// Positions, and per-vertex colours (the mean of the texture at the vertex's corners) as a fallback.
  TriangleMesh mesh;
  std::vector<int> page;  ///< per triangle: its texture page
  /// Per triangle corner (the mesh's corner order): texture coordinates on its page, (0, 0) the top-left
  /// corner of the top-left texel, v growing downwards (glTF's convention; OBJ's vt is (u, 1 - v)).
  std::vector<std::array<Eigen::Vector2f, 3>> uv;
  /// Per triangle: the unit face normal and the tangent frame of its normal map: xyz the direction of +u on
  /// the surface, w the handedness (glTF: bitangent = cross(normal, tangent.xyz) * w points up the image,
  /// -v).
  std::vector<Eigen::Vector3f> face_normal;
  std::vector<Eigen::Vector4f> tangent;
  std::vector<TexturePage> pages;
  AtlasLayout layout;
  /// The range of the depth textures over all pages [m] (both 0 without depth textures).
  float depth_min = 0, depth_max = 0;
};

/// Packs the patches (one per triangle of `mesh`, as computeTexturePatches made them) into pages and
/// assembles the textured mesh. The normal map stores each texel's normal in its triangle's tangent frame,
/// (n.t, n.b, n.N) mapped to [0, 255]. Throws std::invalid_argument if the counts disagree.
TexturedMesh buildTexturedMesh(const TriangleMesh& mesh, const std::vector<TrianglePatches>& patches,
                               const AtlasOptions& options = {});

/// Bilinear lookup of a page image at texture coordinates (u, v) (clamped to the page), RGB in [0, 1].
Eigen::Vector3f samplePage(const std::vector<Rgba>& image, uint32_t width, uint32_t height, double u,
                           double v);

}  // namespace rc
