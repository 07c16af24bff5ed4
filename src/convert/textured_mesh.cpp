#include "relaxed_connectivity/convert/textured_mesh.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace rc {
namespace {

uint8_t toByte(float value) {
  return uint8_t(std::lround(std::clamp(value, 0.0f, 1.0f) * 255.0f));
}

/// Mip levels in the atlas' pattern: each texel takes the patch that owns most of the 2 x 2 texels below it
/// (ties: the smaller index) and the mean of that patch's texels there; normals are averaged as vectors.
void buildMips(TexturePage& page, int levels) {
  page.mips.clear();
  page.mips.reserve(size_t(levels));  // (the loop keeps pointers to the previous level)
  uint32_t w = page.width, h = page.height;
  const std::vector<Rgba>* color = &page.color;
  const std::vector<Rgba>* normal = &page.normal;
  const std::vector<float>* depth = &page.depth;
  const std::vector<int32_t>* owner = &page.owner;
  for (int level = 1; level <= levels && (w > 1 || h > 1); ++level) {
    TexturePage::Mip mip;
    mip.width = (w + 1) / 2;
    mip.height = (h + 1) / 2;
    const size_t n = size_t(mip.width) * mip.height;
    mip.color.assign(n, Rgba{0, 0, 0, 255});
    if (!normal->empty()) mip.normal.assign(n, Rgba{128, 128, 255, 255});
    if (!depth->empty()) mip.depth.assign(n, 0.0f);
    mip.owner.assign(n, -1);
    for (uint32_t y = 0; y < mip.height; ++y)
      for (uint32_t x = 0; x < mip.width; ++x) {
        size_t below[4];
        int count = 0;
        for (uint32_t dy = 0; dy < 2; ++dy)
          for (uint32_t dx = 0; dx < 2; ++dx)
            if (2 * x + dx < w && 2 * y + dy < h) below[count++] = size_t(2 * y + dy) * w + 2 * x + dx;
        int32_t best = -1;
        int best_votes = 0;
        for (int a = 0; a < count; ++a) {
          const int32_t id = (*owner)[below[a]];
          if (id < 0) continue;
          int votes = 0;
          for (int b = 0; b < count; ++b) votes += (*owner)[below[b]] == id;
          if (votes > best_votes || (votes == best_votes && id < best)) best = id, best_votes = votes;
        }
        const size_t i = size_t(y) * mip.width + x;
        mip.owner[i] = best;
        if (best < 0) continue;
        Eigen::Vector3f c_sum = Eigen::Vector3f::Zero(), n_sum = Eigen::Vector3f::Zero();
        float d_sum = 0;
        for (int a = 0; a < count; ++a) {
          if ((*owner)[below[a]] != best) continue;
          const Rgba& c = (*color)[below[a]];
          c_sum += Eigen::Vector3f(c[0], c[1], c[2]);
          if (!normal->empty()) {
            const Rgba& m = (*normal)[below[a]];
            n_sum += Eigen::Vector3f(m[0], m[1], m[2]) / 127.5f - Eigen::Vector3f::Ones();
          }
          if (!depth->empty()) d_sum += (*depth)[below[a]];
        }
        c_sum /= float(best_votes);
        if (!depth->empty()) mip.depth[i] = d_sum / float(best_votes);
        mip.color[i] = {uint8_t(std::lround(c_sum.x())), uint8_t(std::lround(c_sum.y())),
                        uint8_t(std::lround(c_sum.z())), 255};
        if (!normal->empty()) {
          const Eigen::Vector3f u =
              n_sum.norm() > 0 ? Eigen::Vector3f(n_sum.normalized()) : Eigen::Vector3f::UnitZ();
          mip.normal[i] = {toByte(0.5f + 0.5f * u.x()), toByte(0.5f + 0.5f * u.y()),
                           toByte(0.5f + 0.5f * u.z()), 255};
        }
      }
    page.mips.push_back(std::move(mip));
    const TexturePage::Mip& last = page.mips.back();
    w = last.width, h = last.height;
    color = &last.color, normal = &last.normal, depth = &last.depth, owner = &last.owner;
  }
}

}  // namespace

Eigen::Vector3f samplePage(const std::vector<Rgba>& image, uint32_t width, uint32_t height, double u,
                           double v) {
  return bilinear(int(width), int(height), u * width, v * height, [&](int i, int j) {
    const Rgba& c = image[size_t(j) * width + size_t(i)];
    return Eigen::Vector3f(Eigen::Vector3f(c[0], c[1], c[2]) / 255.0f);
  });
}

TexturedMesh buildTexturedMesh(const TriangleMesh& mesh, const std::vector<TrianglePatches>& patches,
                               const AtlasOptions& options) {
  const size_t T = mesh.triangles.size();
  if (patches.size() != T)
    throw std::invalid_argument("buildTexturedMesh: " + std::to_string(patches.size()) + " patches for " +
                                std::to_string(T) + " triangles");
  const bool normals = T > 0 && !patches[0].normal.texels.empty();
  const bool depths = T > 0 && !patches[0].depth.texels.empty();
  std::vector<PatchShape> shapes(T);
  for (size_t t = 0; t < T; ++t) {
    shapes[t] = patches[t].color.shape;
    if (patches[t].color.texels.empty() ||
        (normals && patches[t].normal.texels.size() != patches[t].color.texels.size()) ||
        (depths && patches[t].depth.texels.size() != patches[t].color.texels.size()))
      throw std::invalid_argument("buildTexturedMesh: triangle " + std::to_string(t) +
                                  " has no colour patch, or a normal or depth patch of another size");
  }
  TexturedMesh out;
  out.mesh.triangles = mesh.triangles;
  out.mesh.vertices.positions = mesh.vertices.positions;
  out.layout = packPatches(shapes, options);
  const int P = out.layout.page_size;
  out.pages.resize(size_t(out.layout.pages));
  for (int k = 0; k < out.layout.pages; ++k) {
    TexturePage& page = out.pages[size_t(k)];
    page.width = uint32_t(P);
    page.height = uint32_t(k + 1 == out.layout.pages ? out.layout.last_page_height : P);
    page.color.assign(size_t(page.width) * page.height, Rgba{0, 0, 0, 255});
    page.owner.assign(page.color.size(), -1);
    if (normals) page.normal.assign(page.color.size(), Rgba{128, 128, 255, 255});
    if (depths) page.depth.assign(page.color.size(), 0.0f);
  }
  if (depths) {
    out.depth_min = std::numeric_limits<float>::infinity();
    out.depth_max = -out.depth_min;
  }
  out.page.resize(T);
  out.uv.resize(T);
  out.face_normal.resize(T);
  out.tangent.resize(T);
  std::vector<Eigen::Vector3f> vertex_color_sum(mesh.vertices.size(), Eigen::Vector3f::Zero());
  std::vector<int> vertex_corners(mesh.vertices.size(), 0);
  for (size_t t = 0; t < T; ++t) {
    const TrianglePatches& p = patches[t];
    const PatchPlacement& place = out.layout.placements[t];
    TexturePage& page = out.pages[size_t(place.page)];
    out.page[t] = place.page;
    // The page-texel -> surface map of this patch (rigid: a rotation, possibly mirrored, at 1 / tpu).
    const Triangle& tri = mesh.triangles[t];
    const std::array<Vec3, 3> P3 = {mesh.vertices.positions[tri[p.frame.corner[0]]],
                                    mesh.vertices.positions[tri[p.frame.corner[1]]],
                                    mesh.vertices.positions[tri[p.frame.corner[2]]]};
    Eigen::Matrix2d M;
    M.col(0) = place.corners[1] - place.corners[0];
    M.col(1) = place.corners[2] - place.corners[0];
    Eigen::Matrix<double, 3, 2> E;
    E.col(0) = P3[1] - P3[0];
    E.col(1) = P3[2] - P3[0];
    const Eigen::Matrix<double, 3, 2> d_surface = E * M.inverse();  // columns: d/d(page x), d/d(page row)
    const Vec3 N = p.frame.normal, t_axis = d_surface.col(0).normalized();
    const Vec3 up = -d_surface.col(1).normalized();  // up the image: decreasing rows
    out.face_normal[t] = N.cast<float>();
    out.tangent[t] = Eigen::Vector4f(float(t_axis.x()), float(t_axis.y()), float(t_axis.z()),
                                     N.cross(t_axis).dot(up) >= 0 ? 1.0f : -1.0f);
    const Vec3 b_axis = N.cross(t_axis) * double(out.tangent[t].w());
    for (int c = 0; c < 3; ++c) {
      const Eigen::Vector2d& q = place.corners[size_t(c)];
      out.uv[t][size_t(p.frame.corner[size_t(c)])] =
          Eigen::Vector2f(float(q.x() / page.width), float(q.y() / page.height));
    }
    // Blit the patch raster (its mask frame) to the page with the placement's flips: mask texel (x, y) lands
    // on page texel (left + x or left + W-1-x, top + y or top + H-1-y).
    const TexturePatch& cp = p.color;
    const int W = cp.width, H = cp.height;
    const double o = cp.origin;
    const int left = int(
        std::lround(place.flipped_horizontally ? place.corners[0].x() - (W - o) : place.corners[0].x() - o));
    const int top = int(
        std::lround(place.flipped_vertically ? place.corners[0].y() - (H - o) : place.corners[0].y() - o));
    const PatchMask mask = patchMask(cp.shape, options.border);
    if (mask.width != W || mask.height != H)  // (the patches were made with another border)
      throw std::invalid_argument("buildTexturedMesh: triangle " + std::to_string(t) + "'s patch is " +
                                  std::to_string(W) + " x " + std::to_string(H) +
                                  " texels, its mask at border " + std::to_string(options.border) + " " +
                                  std::to_string(mask.width) + " x " + std::to_string(mask.height) +
                                  ": TextureOptions::border must equal AtlasOptions::border");
    for (int y = 0; y < H; ++y)
      for (int x = 0; x < W; ++x) {
        if (!mask.texels[size_t(y) * W + x]) continue;
        const int px = left + (place.flipped_horizontally ? W - 1 - x : x);
        const int py = top + (place.flipped_vertically ? H - 1 - y : y);
        const size_t dst = size_t(py) * page.width + size_t(px), src = size_t(y) * W + x;
        const Eigen::Vector3f& c = cp.texels[src];
        page.owner[dst] = int32_t(t);
        page.color[dst] = {toByte(c.x()), toByte(c.y()), toByte(c.z()), 255};
        if (normals) {
          const Vec3 n = p.normal.texels[src].cast<double>().normalized();
          page.normal[dst] = {toByte(float(0.5 + 0.5 * n.dot(t_axis))),
                              toByte(float(0.5 + 0.5 * n.dot(b_axis))), toByte(float(0.5 + 0.5 * n.dot(N))),
                              255};
        }
        if (depths) {
          const float d = p.depth.texels[src].x();
          page.depth[dst] = d;
          out.depth_min = std::min(out.depth_min, d);
          out.depth_max = std::max(out.depth_max, d);
        }
      }
    for (int c = 0; c < 3; ++c) {
      const Eigen::Vector2f& q = out.uv[t][size_t(c)];
      vertex_color_sum[tri[size_t(c)]] += samplePage(page.color, page.width, page.height, q.x(), q.y());
      ++vertex_corners[tri[size_t(c)]];
    }
  }
  if (options.mip_levels < 0) throw std::invalid_argument("buildTexturedMesh: mip_levels must be >= 0");
  for (TexturePage& page : out.pages) buildMips(page, options.mip_levels);
  out.mesh.vertices.colors.resize(mesh.vertices.size(), Rgba{200, 200, 200, 255});
  for (size_t v = 0; v < mesh.vertices.size(); ++v)
    if (vertex_corners[v]) {
      const Eigen::Vector3f c = vertex_color_sum[v] / float(vertex_corners[v]);
      out.mesh.vertices.colors[v] = {toByte(c.x()), toByte(c.y()), toByte(c.z()), 255};
    }
  return out;
}

}  // namespace rc
