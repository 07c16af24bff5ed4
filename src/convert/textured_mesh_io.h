// Files for a textured mesh (thesis 6): Wavefront OBJ + MTL + PNG pages (colour, tangent-space normal map),
// which MeshLab and Blender open, and glTF 2.0 binary (.glb, through tinygltf) for any glTF viewer.
// Per-vertex colours ride along in the OBJ (v x y z r g b) for tools that ignore textures.
#pragma once

#include <string>
#include <vector>

#include "relaxed_connectivity/convert/textured_mesh.h"

namespace rc {

/// Writes <stem>.obj, <stem>.mtl and per page <stem>_color<k>.png and (with normal maps) <stem>_normal<k>.png
/// beside it (`obj_path` names the .obj), with depth textures <stem>_depth<k>.png (16-bit grey: 0 .. 65535
/// span depth_min .. depth_max, the MTL's `disp -mm base gain`), and the pages' atlas-pattern mip levels as
/// <stem>_color<k>_mip<L>.png (MTL has no way to name them: for engines that load their own mip chains).
/// Faces carry their face normal (the normal map's frame) and one material per page (map_Kd, and map_Bump for
/// the normal map). Returns the files written. Throws std::runtime_error naming the file that could not be
/// written.
std::vector<std::string> writeTexturedObj(const std::string& obj_path, const TexturedMesh& mesh);

/// True when this build has tinygltf (libtinygltf-dev); writeGlb throws std::runtime_error otherwise.
bool glbAvailable();

/// Writes a glTF 2.0 binary: one mesh with a primitive per page (POSITION, NORMAL, TANGENT, TEXCOORD_0,
/// unindexed corners), one material per page (base colour texture, normal texture; metallic 0, roughness 1),
/// the PNG pages embedded (level 0 only: glTF stores no mip chain in PNG; no depth: glTF 2.0 has no
/// displacement map), and the node rotated from ROS'
/// z-up to glTF's y-up. Throws std::runtime_error
/// naming the file on failure.
void writeGlb(const std::string& path, const TexturedMesh& mesh);

}  // namespace rc
