#include "relaxed_connectivity/convert/textured_mesh_renderer.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace rc {

MeshImage renderTexturedMesh(const TexturedMesh& mesh, const Camera& camera, Rgba background) {
  camera.validate();
  MeshImage image;
  image.width = camera.width;
  image.height = camera.height;
  const size_t n = size_t(image.width) * image.height;
  image.color.assign(n, background);
  image.depth.assign(n, std::numeric_limits<float>::infinity());
  const bool perspective = camera.projection == Camera::Projection::kPerspective;
  const Eigen::Isometry3d camera_T_world = camera.world_T_camera.inverse();
  for (size_t t = 0; t < mesh.mesh.triangles.size(); ++t) {
    const Triangle& tri = mesh.mesh.triangles[t];
    const TexturePage& page = mesh.pages[size_t(mesh.page[t])];
    double u[3], v[3], z[3];
    bool visible = true;
    for (int c = 0; c < 3; ++c) {
      const Vec3 p = camera_T_world * mesh.mesh.vertices.positions[tri[size_t(c)]];
      visible = visible && camera.project(p, &u[c], &v[c]);
      z[c] = p.z();
    }
    if (!visible) continue;  // (a triangle crossing the near plane is skipped, not clipped)
    const double area = (u[1] - u[0]) * (v[2] - v[0]) - (u[2] - u[0]) * (v[1] - v[0]);
    if (!(std::abs(area) > 1e-12)) continue;
    const int x0 = std::max(0, int(std::ceil(std::min({u[0], u[1], u[2]}))));
    const int x1 = std::min(int(image.width) - 1, int(std::floor(std::max({u[0], u[1], u[2]}))));
    const int y0 = std::max(0, int(std::ceil(std::min({v[0], v[1], v[2]}))));
    const int y1 = std::min(int(image.height) - 1, int(std::floor(std::max({v[0], v[1], v[2]}))));
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) {
        // Screen-space barycentrics (pixel centres at integers), then perspective-correct ones.
        double b[3];
        for (int c = 0; c < 3; ++c) {
          const int c1 = (c + 1) % 3, c2 = (c + 2) % 3;
          b[c] = ((u[c1] - x) * (v[c2] - y) - (u[c2] - x) * (v[c1] - y)) / area;
        }
        if (b[0] < 0 || b[1] < 0 || b[2] < 0) continue;
        double w[3], sum = 0;
        for (int c = 0; c < 3; ++c) sum += w[c] = perspective ? b[c] / z[c] : b[c];
        for (double& wc : w) wc /= sum;
        const double depth = w[0] * z[0] + w[1] * z[1] + w[2] * z[2];
        const size_t i = size_t(y) * image.width + size_t(x);
        if (!(depth < image.depth[i])) continue;
        image.depth[i] = float(depth);
        const Eigen::Vector2f uv =
            float(w[0]) * mesh.uv[t][0] + float(w[1]) * mesh.uv[t][1] + float(w[2]) * mesh.uv[t][2];
        const Eigen::Vector3f c = samplePage(page.color, page.width, page.height, uv.x(), uv.y());
        image.color[i] = {uint8_t(std::lround(255 * c.x())), uint8_t(std::lround(255 * c.y())),
                          uint8_t(std::lround(255 * c.z())), 255};
      }
  }
  return image;
}

ImageComparison compareImages(const std::vector<Rgba>& a, const std::vector<float>& a_depth,
                              const std::vector<Rgba>& b, const std::vector<float>& b_depth) {
  if (a.size() != b.size() || a.size() != a_depth.size() || b.size() != b_depth.size())
    throw std::invalid_argument("compareImages: the images differ in size");
  ImageComparison r;
  double sum = 0;
  size_t either = 0, one = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    const bool fa = std::isfinite(a_depth[i]), fb = std::isfinite(b_depth[i]);
    either += fa || fb;
    one += fa != fb;
    if (!fa || !fb) continue;
    for (int c = 0; c < 3; ++c) {
      const double d = double(a[i][c]) - double(b[i][c]);
      sum += d * d;
    }
    ++r.compared;
  }
  r.mse = r.compared ? sum / (3.0 * double(r.compared)) : 0.0;
  r.psnr = r.mse > 0 ? 10 * std::log10(255.0 * 255.0 / r.mse) : std::numeric_limits<double>::infinity();
  r.silhouette_mismatch = either ? double(one) / double(either) : 0.0;
  return r;
}

}  // namespace rc
