// Procedurally generated test models with analytic structure (so the scanning demo works without any data
// files). Every closed model is watertight (each edge shared by exactly two triangles, outward
// counter-clockwise winding) and carries unit vertex normals and RGBA vertex colours. World frame: z up,
// models centred at the origin, sizes around one metre.
#pragma once

#include <string>
#include <vector>

#include "relaxed_connectivity/core/triangle_mesh.h"

namespace rc {

/// Geodesic sphere: each icosahedron edge split into `frequency` segments, vertices projected onto the
/// sphere. 20 * frequency^2 triangles.
TriangleMesh makeIcosphere(double radius, int frequency);

/// Latitude/longitude sphere with single pole vertices: 2 * segments * (rings - 1) triangles
/// (segments >= 3, rings >= 2).
TriangleMesh makeUvSphere(double radius, int segments, int rings);

/// Torus around the z axis: 2 * major_segments * minor_segments triangles (both >= 3, minor < major radius).
TriangleMesh makeTorus(double major_radius, double minor_radius, int major_segments, int minor_segments);

/// Axis-aligned box centred at the origin with `subdivisions` segments per edge: 12 * subdivisions^2
/// triangles. Vertex normals are area-weighted (so they are diagonal on the box edges).
TriangleMesh makeBox(const Vec3& size, int subdivisions);

/// Star-shaped "blob": an icosphere whose radius along unit direction d is blobRadius(d, radius, amplitude).
TriangleMesh makeBlob(double radius, double amplitude, int frequency);
/// radius * (1 + amplitude * f(d)) with a fixed smooth |f| <= 1 (low-order spherical harmonics).
double blobRadius(const Vec3& unit_direction, double radius, double amplitude);

/// (p, q) torus knot centre line: ((R + r cos q s) cos p s, (R + r cos q s) sin p s, r sin q s), s in [0, 2
/// pi).
Vec3 torusKnotPoint(int p, int q, double major_radius, double minor_radius, double s);
/// Circular tube of `tube_radius` around the torus knot: 2 * segments_along * segments_around triangles.
TriangleMesh makeTorusKnot(int p, int q, double major_radius, double minor_radius, double tube_radius,
                           int segments_along, int segments_around);

/// Square ground plane z = height with normal +z (open: its outer border edges belong to one triangle),
/// 2 * subdivisions^2 triangles, uniform grey.
TriangleMesh makeGroundPlane(double height, double half_size, int subdivisions);

/// Appends `src` to `dst` (indices shifted). Channels present in only one of them are dropped.
void appendMesh(TriangleMesh& dst, const TriangleMesh& src);
/// Sets unit area-weighted vertex normals from the triangle geometric normals.
void computeVertexNormals(TriangleMesh& mesh);

/// Names accepted by makeModel().
const std::vector<std::string>& modelNames();
/// Model by name, with `resolution` (>= 1) controlling the tessellation (triangle counts grow with
/// resolution^2): icosphere 20 r^2, uv_sphere 4 r^2, torus 4 r^2, box 12 r^2, blob 20 r^2, torus_knot 16 r^2
/// (r >= 3 for the sphere/torus/knot). With `with_ground_plane`, a ground plane just below the model is added
/// (the result is then not closed). Throws std::invalid_argument for an unknown name (listing the valid ones)
/// or a bad resolution.
TriangleMesh makeModel(const std::string& name, int resolution, bool with_ground_plane = false);

}  // namespace rc
