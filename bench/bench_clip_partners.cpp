// Clipping partners per frame (thesis 4.2.1): clip buffer (Algorithm 4.1) vs spatial index (kd-tree range
// query), on a cube with 900 surfels per face and a sphere minus four spheres (~100k surfels), both built
// here. Times are medians of 5 runs; both methods must return identical partner sets.
#include <omp.h>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <vector>

#include "relaxed_connectivity/render/csg/clip_partners.h"
#include "relaxed_connectivity/render/csg/csg_clipper.h"
#include "relaxed_connectivity/render/splat/camera.h"

using namespace rc;

namespace {

struct CsgScene {
  const char* name;
  SurfelCloud cloud;
  CsgTree tree;
  Camera camera;
};

void addSurfel(SurfelCloud& c, std::vector<int>& patch, const Vec3& p, const Vec3& n, double r, int id) {
  c.positions.push_back(p);
  c.normals.push_back(n.normalized());
  c.radii.push_back(r);
  patch.push_back(id);
}

void setPatches(SurfelCloud& c, const std::vector<int>& patch) {
  Attribute& a = c.attributes.add("patch_id", ScalarType::kInt32, 1, c.size());
  for (size_t i = 0; i < patch.size(); ++i) a.set(i, patch[i]);
}

CsgScene cube900() {
  CsgScene s{"cube 6 x 900",
             {},
             CsgTree::parse("((0 & 1) & (2 & 3)) & (4 & 5)"),
             Camera::perspective(640, 480, 0.9)};
  std::vector<int> patch;
  const Vec3 axes[3] = {Vec3::UnitX(), Vec3::UnitY(), Vec3::UnitZ()};
  const int k = 30;
  const double h = 2.0 / k;
  for (int f = 0; f < 6; ++f) {
    const Vec3 n = (f % 2 ? -1.0 : 1.0) * axes[f / 2], u = axes[(f / 2 + 1) % 3], v = n.cross(u);
    for (int i = 0; i < k; ++i)
      for (int j = 0; j < k; ++j)
        addSurfel(s.cloud, patch, n + (-1 + (i + 0.5) * h) * u + (-1 + (j + 0.5) * h) * v, n, 0.75 * h, f);
  }
  setPatches(s.cloud, patch);
  s.camera.lookAt(Vec3(3.2, -2.6, 2.4), Vec3(0, 0, 0));
  return s;
}

// Fibonacci sampling of a sphere; `inward` flips the normals (not needed for partners, kept for realism).
void sphere(SurfelCloud& c, std::vector<int>& patch, const Vec3& centre, double radius, int n, int id) {
  const double golden = std::acos(-1.0) * (3 - std::sqrt(5.0));
  const double r_surfel = 0.8 * radius * std::sqrt(4.0 / n);
  for (int i = 0; i < n; ++i) {
    const double z = 1 - 2 * (i + 0.5) / n, rho = std::sqrt(1 - z * z), phi = golden * i;
    const Vec3 d(rho * std::cos(phi), rho * std::sin(phi), z);
    addSurfel(c, patch, centre + radius * d, d, r_surfel, id);
  }
}

CsgScene sphereMinusSpheres() {
  CsgScene s{"sphere - 4 spheres",
             {},
             CsgTree::parse("0 - (((1 | 2) | 3) | 4)"),
             Camera::perspective(640, 480, 0.9)};
  std::vector<int> patch;
  sphere(s.cloud, patch, Vec3(0, 0, 0), 1.0, 80000, 0);
  const Vec3 centres[4] = {Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1), Vec3(-0.6, -0.6, -0.53)};
  for (int k = 0; k < 4; ++k) sphere(s.cloud, patch, centres[k], 0.45, 5000, k + 1);
  setPatches(s.cloud, patch);
  s.camera.lookAt(Vec3(2.6, 2.2, 1.8), Vec3(0, 0, 0));
  return s;
}

template <class F>
double medianMs(F&& f) {
  std::vector<double> t;
  for (int r = 0; r < 5; ++r) {
    const auto a = std::chrono::steady_clock::now();
    f();
    t.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - a).count());
  }
  std::sort(t.begin(), t.end());
  return t[2];
}

}  // namespace

int main() {
  std::printf("threads: %d\n", omp_get_max_threads());
  std::printf("%-20s %8s %-10s %7s %8s %12s %12s %8s %s\n", "scene", "surfels", "candidates", "edge", "pairs",
              "clipbuf_ms", "spatial_ms", "cb/sp", "equal");
  for (CsgScene scene : {cube900(), sphereMinusSpheres()}) {
    const SurfelDiscs discs = SurfelDiscs::fromCloud(scene.cloud);
    CsgClipper clipper(scene.cloud, scene.tree);
    const std::vector<uint32_t>& edges = clipper.edgeSurfels();
    for (int pass = 0; pass < 2; ++pass) {
      const std::vector<uint32_t>* cand = pass == 0 ? nullptr : &edges;
      ClipPartnerFinder finder;
      ClipPartners a, b;
      ClipPartnerStats sa, sb;
      const double t_buffer = medianMs([&] { finder.findClipBuffer(discs, scene.camera, &a, cand, &sa); });
      const double t_spatial = medianMs([&] { finder.findSpatial(discs, &b, cand, &sb); });
      std::printf("%-20s %8zu %-10s %7zu %8zu %12.2f %12.2f %8.2f %s\n", scene.name, discs.size(),
                  pass == 0 ? "all" : "edge", edges.size(), sa.pairs, t_buffer, t_spatial,
                  t_buffer / t_spatial, a == b ? "yes" : "NO");
      std::printf("    clip buffer: %zu cell entries, %zu edge-on, %zu pair tests; spatial: %zu pair tests\n",
                  sb.candidates ? sa.cell_entries : 0, sa.edge_on, sa.tested_pairs, sb.tested_pairs);
    }
  }
  return 0;
}
