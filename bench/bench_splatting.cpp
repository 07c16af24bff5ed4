// Software EWA splatting throughput (thesis 3.2): splats per second for a sampled sphere at 1280x720, 1 and 2
// threads, median (min-max) of N frames after a warm-up frame (scratch memory is reused), per-pass breakdown
// (visibility, accumulation and shading run per tile: thread-summed time / threads), the machine (CPU model,
// cores, SIMD path, load average), and peers measured in the same process on the same surfels, camera and
// resolution, their frames interleaved with ours (A B C A B C ...) so that background load hits all alike:
//  - the four-wide SSE2 passes of our renderer (the default uses AVX2 where the CPU has it; same image);
//  - a plain z-buffered disc rasterizer written here (PlainDiscRasterizer): each surfel is drawn as its
//    projected disc (the ellipse of the disc's affine projection at its centre) with a per-pixel depth test
//    against the disc's plane; the nearest fragment wins. No EWA low-pass filter, no blending or weight
//    normalisation, no fuzzy depth test, flat (per-surfel Lambert) shading instead of per-pixel Phong; writes
//    colour and depth only. Same thread count (rows split into interleaved 16-row bands per thread);
//  - VTK's vtkPointGaussianMapper drawing the surfels as opaque screen-aligned discs through OpenGL
//  off-screen
//    (Mesa llvmpipe under Xvfb on machines without a GPU), only when an X display is usable (run under
//    `xvfb-run -a`); otherwise a skip line is printed.
// Then the cost of the EWA filter and of the depth tolerance against quality (holes inside the analytic
// silhouette, seam angle between neighbouring pixels), and of exact silhouettes against the filtered
// footprint.
//   bench_splatting [--frames N] [--quick] [--silhouettes]
#include <fcntl.h>
#include <omp.h>
#include <sched.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <string>
#include <thread>
#include <vector>

#include "relaxed_connectivity/render/splat/surfel_renderer.h"

#if defined(RC_HAVE_PCL) && defined(__has_include)
#if __has_include(<vtkPointGaussianMapper.h>) && __has_include(<vtkAutoInit.h>)
#define RC_BENCH_VTK_PEER 1
#endif
#endif

#ifdef RC_BENCH_VTK_PEER
#include <vtkAutoInit.h>
VTK_MODULE_INIT(vtkRenderingOpenGL2);
#include <vtkActor.h>
#include <vtkCamera.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPointGaussianMapper.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkRenderWindow.h>
#include <vtkRenderer.h>
#include <vtkUnsignedCharArray.h>
#include <vtkVersion.h>
#endif

namespace {

using rc::Vec3;
using Clock = std::chrono::steady_clock;

double msSince(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

rc::SurfelCloud sampleSphere(double radius, int count) {
  rc::SurfelCloud cloud;
  cloud.positions.reserve(count);
  cloud.normals.reserve(count);
  cloud.radii.assign(count, 1.5 * radius * std::sqrt(4.0 / count));
  cloud.colors.assign(count, rc::Rgba{200, 120, 60, 255});
  const double golden = M_PI * (3.0 - std::sqrt(5.0));
  for (int i = 0; i < count; ++i) {
    const double z = 1 - 2 * (i + 0.5) / count, r = std::sqrt(1 - z * z), phi = golden * i;
    const Vec3 normal(r * std::cos(phi), r * std::sin(phi), z);
    cloud.normals.push_back(normal);
    cloud.positions.push_back(radius * normal);
  }
  return cloud;
}

// ---------------------------------------------------------------------------------------------------------
// Machine description
// ---------------------------------------------------------------------------------------------------------

std::string readFile(const char* path) {
  std::FILE* f = std::fopen(path, "r");
  if (!f) return "";
  std::string s;
  char buf[4096];
  size_t n;
  while ((n = std::fread(buf, 1, sizeof(buf), f)) > 0) s.append(buf, n);
  std::fclose(f);
  return s;
}

/// Value of the first "key : value" line of /proc/cpuinfo.
std::string cpuinfoField(const std::string& cpuinfo, const char* key) {
  size_t pos = 0;
  while (pos < cpuinfo.size()) {
    const size_t end = std::min(cpuinfo.find('\n', pos), cpuinfo.size());
    const std::string line = cpuinfo.substr(pos, end - pos);
    if (line.compare(0, std::strlen(key), key) == 0) {
      const size_t colon = line.find(':');
      if (colon != std::string::npos) return line.substr(line.find_first_not_of(" \t", colon + 1));
    }
    pos = end + 1;
  }
  return "?";
}

bool hasFlag(const std::string& flags, const char* flag) {
  return (" " + flags + " ").find(" " + std::string(flag) + " ") != std::string::npos;
}

std::string loadAverage() {
  const std::string s = readFile("/proc/loadavg");
  size_t pos = 0;
  for (int i = 0; i < 3 && pos != std::string::npos; ++i) pos = s.find(' ', pos + 1);
  return s.empty() ? "?" : s.substr(0, pos);
}

void printMachine(int simd_width) {
  const std::string cpuinfo = readFile("/proc/cpuinfo");
  const std::string flags = cpuinfoField(cpuinfo, "flags");
  cpu_set_t set;
  CPU_ZERO(&set);
  const int usable = sched_getaffinity(0, sizeof(set), &set) == 0 ? CPU_COUNT(&set) : -1;
  std::printf("machine: %s (family %s, model %s, stepping %s, %s MHz, cache %s)\n",
              cpuinfoField(cpuinfo, "model name").c_str(), cpuinfoField(cpuinfo, "cpu family").c_str(),
              cpuinfoField(cpuinfo, "model\t").c_str(), cpuinfoField(cpuinfo, "stepping").c_str(),
              cpuinfoField(cpuinfo, "cpu MHz").c_str(), cpuinfoField(cpuinfo, "cache size").c_str());
  std::printf(
      "nproc %d (hardware threads %u), OpenMP max threads %d; CPU flags: avx2 %s, fma %s, avx512f %s; "
      "renderer's unclipped tile passes: %d-wide (%s); hypervisor: %s\n",
      usable, std::thread::hardware_concurrency(), omp_get_max_threads(),
      hasFlag(flags, "avx2") ? "yes" : "no", hasFlag(flags, "fma") ? "yes" : "no",
      hasFlag(flags, "avx512f") ? "yes" : "no", simd_width,
      simd_width == 8   ? "AVX2 used"
      : simd_width == 4 ? "SSE2, no AVX2"
                        : "scalar",
      hasFlag(flags, "hypervisor") ? "yes (virtual machine)" : "no");
  const char* wait_policy = std::getenv("OMP_WAIT_POLICY");
  std::printf("load average at start: %s; OMP_WAIT_POLICY=%s\n", loadAverage().c_str(),
              wait_policy ? wait_policy : "(unset)");
}

// ---------------------------------------------------------------------------------------------------------
// Peer: a plain z-buffered disc rasterizer
// ---------------------------------------------------------------------------------------------------------

/// Each surfel as its projected disc with a depth test, nearest wins: the simple, non-EWA baseline. The disc
/// {c + s r t1 + t r t2 : s^2 + t^2 <= 1} is projected affinely at its centre (the screen ellipse spanned by
/// J r t1 and J r t2, J the Jacobian of the projection) and its depth is the plane's, linear in the pixel.
/// Colour: the surfel colour times a per-surfel Lambert term (same light as the renderer). Set-up is one
/// parallel loop; rasterization is by scanline (each row's span of the ellipse solved from its quadratic),
/// each thread owning the rows of every (threads)-th band of 16 rows and walking all discs in input order
/// (deterministic).
class PlainDiscRasterizer {
 public:
  PlainDiscRasterizer(int threads, bool backface_culling) : threads_(threads), cull_(backface_culling) {}

  void render(const rc::SurfelCloud& cloud, const rc::Camera& camera, std::vector<rc::Rgba>* color,
              std::vector<float>* depth, double* setup_ms = nullptr) {
    const auto t0 = Clock::now();
    const int w = int(camera.width), h = int(camera.height);
    const size_t n = cloud.size();
    discs_.resize(n);
    const Eigen::Isometry3d camera_T_world = camera.world_T_camera.inverse();
    const Eigen::Matrix3d rot = camera_T_world.linear();
    const Vec3 light = -rc::SplatConfig().light_direction_camera.normalized();  // towards the light
    const bool perspective = camera.projection == rc::Camera::Projection::kPerspective;
#pragma omp parallel for num_threads(threads_) schedule(static)
    for (size_t i = 0; i < n; ++i) {
      Disc& d = discs_[i];
      d.valid = false;
      const Vec3 p = camera_T_world * cloud.positions[i];
      if (p.z() <= camera.near_clip) continue;
      Vec3 nc = rot * cloud.normals[i];
      const double facing = perspective ? nc.dot(p) : nc.z();
      if (facing > 0) {
        if (cull_) continue;
        nc = -nc;  // two-sided: the back side faces the camera
      }
      // Tangent frame (Duff et al.'s branchless basis).
      const double sign = std::copysign(1.0, nc.z()), a = -1.0 / (sign + nc.z()), b = nc.x() * nc.y() * a;
      const Vec3 t1(1 + sign * nc.x() * nc.x() * a, sign * b, -sign * nc.x()),
          t2(b, sign + nc.y() * nc.y() * a, -nc.y());
      const double r = cloud.radii[i];
      double u, v, j00, j02, j11, j12;
      if (perspective) {
        const double iz = 1.0 / p.z();
        u = camera.fx * p.x() * iz + camera.cx;
        v = camera.fy * p.y() * iz + camera.cy;
        j00 = camera.fx * iz;
        j02 = -camera.fx * p.x() * iz * iz;
        j11 = camera.fy * iz;
        j12 = -camera.fy * p.y() * iz * iz;
      } else {
        u = camera.ortho_scale * p.x() + camera.cx;
        v = camera.ortho_scale * p.y() + camera.cy;
        j00 = j11 = camera.ortho_scale;
        j02 = j12 = 0;
      }
      const double ax = r * (j00 * t1.x() + j02 * t1.z()), ay = r * (j11 * t1.y() + j12 * t1.z());
      const double bx = r * (j00 * t2.x() + j02 * t2.z()), by = r * (j11 * t2.y() + j12 * t2.z());
      const double det = ax * by - ay * bx;
      if (std::abs(det) < 1e-3) continue;  // edge-on sliver
      const double ex = std::sqrt(ax * ax + bx * bx), ey = std::sqrt(ay * ay + by * by);
      if (u + ex < 0 || u - ex > w - 1 || v + ey < 0 || v - ey > h - 1) continue;
      // (s, t) = M^-1 (dx, dy) with M = [a b]; inside if s^2 + t^2 <= 1.
      const double i00 = by / det, i01 = -bx / det, i10 = -ay / det, i11 = ax / det;
      d.qa = float(i00 * i00 + i10 * i10);
      d.qb = float(2 * (i00 * i01 + i10 * i11));
      d.qc = float(i01 * i01 + i11 * i11);
      // depth z = p.z + s r t1.z + t r t2.z
      d.gx = float(r * (t1.z() * i00 + t2.z() * i10));
      d.gy = float(r * (t1.z() * i01 + t2.z() * i11));
      d.u = float(u);
      d.v = float(v);
      d.z = float(p.z());
      d.x0 = std::max(0, int(std::ceil(u - ex)));
      d.x1 = std::min(w - 1, int(std::floor(u + ex)));
      d.y0 = std::max(0, int(std::ceil(v - ey)));
      d.y1 = std::min(h - 1, int(std::floor(v + ey)));
      const double shade = 0.25 + 0.7 * std::max(0.0, nc.dot(light));
      const rc::Rgba c = cloud.colors.empty() ? rc::Rgba{200, 200, 200, 255} : cloud.colors[i];
      for (int k = 0; k < 3; ++k) d.color[k] = uint8_t(std::min(255.0, c[k] * shade));
      d.color[3] = 255;
      d.valid = d.x0 <= d.x1 && d.y0 <= d.y1;
    }
    if (setup_ms) *setup_ms = msSince(t0);
    color->resize(size_t(w) * h);
    depth->resize(size_t(w) * h);
#pragma omp parallel num_threads(threads_)
    {
      const int me = omp_get_thread_num(), team = omp_get_num_threads();
      for (int y = 0; y < h; ++y)
        if ((y >> 4) % team == me) {
          std::fill_n(color->data() + size_t(y) * w, w, rc::Rgba{255, 255, 255, 255});
          std::fill_n(depth->data() + size_t(y) * w, w, std::numeric_limits<float>::infinity());
        }
      for (const Disc& d : discs_) {
        if (!d.valid) continue;
        for (int band = d.y0 >> 4; band <= d.y1 >> 4; ++band) {
          if (band % team != me) continue;
          for (int y = std::max(d.y0, band << 4), y_end = std::min(d.y1, (band << 4) | 15); y <= y_end; ++y) {
            // The row's span of the ellipse qa dx^2 + qb dx dy + qc dy^2 <= 1 (a scanline rasterizer).
            const float dy = float(y) - d.v;
            const float half_b = 0.5f * d.qb * dy, disc = half_b * half_b - d.qa * (d.qc * dy * dy - 1.0f);
            if (disc < 0) continue;
            const float root = std::sqrt(disc), inv_a = 1.0f / d.qa;
            const int xa = std::max(d.x0, int(std::ceil(d.u + (-half_b - root) * inv_a)));
            const int xb = std::min(d.x1, int(std::floor(d.u + (-half_b + root) * inv_a)));
            float* zrow = depth->data() + size_t(y) * w;
            rc::Rgba* crow = color->data() + size_t(y) * w;
            const float z_row = d.z + d.gy * dy;
            for (int x = xa; x <= xb; ++x) {
              const float z = z_row + d.gx * (float(x) - d.u);
              if (z < zrow[x]) {
                zrow[x] = z;
                crow[x] = d.color;
              }
            }
          }
        }
      }
    }
  }

 private:
  struct Disc {
    float u, v, z, gx, gy, qa, qb, qc;
    int x0, x1, y0, y1;
    rc::Rgba color;
    bool valid;
  };
  int threads_;
  bool cull_;
  std::vector<Disc> discs_;
};

// ---------------------------------------------------------------------------------------------------------
// Peer: VTK vtkPointGaussianMapper off-screen (OpenGL; Mesa llvmpipe without a GPU)
// ---------------------------------------------------------------------------------------------------------

#ifdef RC_BENCH_VTK_PEER
/// Opaque screen-aligned discs: the fragment shader discards outside the unit circle; the bounding
/// triangle is shrunk to the disc (TriangleScale 1; the default 3 is for Gaussians and draws 9x the area).
const char* const kVtkDiscShader =
    "//VTK::Color::Impl\n"
    "float dist2 = dot(offsetVCVSOutput.xy, offsetVCVSOutput.xy);\n"
    "if (dist2 > 1.0) { discard; }\n";

struct VtkTiming {
  std::vector<double> cached, upload;
  size_t covered = 0;
  std::string renderer;
};

VtkTiming vtkFrames(const rc::SurfelCloud& cloud, const rc::Camera& camera, int frames) {
  VtkTiming out;
  vtkNew<vtkPoints> points;
  points->SetDataTypeToFloat();
  points->SetNumberOfPoints(vtkIdType(cloud.size()));
  vtkNew<vtkUnsignedCharArray> colors;
  colors->SetNumberOfComponents(3);
  colors->SetName("colors");
  colors->SetNumberOfTuples(vtkIdType(cloud.size()));
  for (size_t i = 0; i < cloud.size(); ++i) {
    points->SetPoint(vtkIdType(i), cloud.positions[i].data());
    const rc::Rgba c = cloud.colors[i];
    const unsigned char rgb[3] = {c[0], c[1], c[2]};
    colors->SetTypedTuple(vtkIdType(i), rgb);
  }
  vtkNew<vtkPolyData> poly;
  poly->SetPoints(points);
  poly->GetPointData()->SetScalars(colors);
  vtkNew<vtkPointGaussianMapper> mapper;
  mapper->SetInputData(poly);
  mapper->SetScaleFactor(cloud.radii.empty() ? 0.01 : cloud.radii[0]);  // constant radius here
  mapper->SetTriangleScale(1.0);
  mapper->EmissiveOff();
  mapper->SetSplatShaderCode(kVtkDiscShader);
  vtkNew<vtkActor> actor;
  actor->SetMapper(mapper);
  vtkNew<vtkRenderer> renderer;
  renderer->AddActor(actor);
  renderer->SetBackground(1, 1, 1);
  vtkNew<vtkRenderWindow> window;
  window->SetOffScreenRendering(1);
  window->SetMultiSamples(0);  // VTK's default of 8 samples is not what a splat renderer does
  window->AddRenderer(renderer);
  window->SetSize(int(camera.width), int(camera.height));
  vtkCamera* cam = renderer->GetActiveCamera();
  const Vec3 eye = camera.world_T_camera.translation();
  const Vec3 forward = camera.world_T_camera.linear().col(2), down = camera.world_T_camera.linear().col(1);
  cam->SetPosition(eye.data());
  const Vec3 focal = eye + forward;
  cam->SetFocalPoint(focal.data());
  const Vec3 up = -down;
  cam->SetViewUp(up.data());
  cam->SetViewAngle(2 * std::atan(0.5 * camera.height / camera.fy) * 180 / M_PI);  // vertical
  cam->SetClippingRange(0.5, 10.0);
  window->Render();  // shader compilation, buffer upload
  window->WaitForCompletion();
  for (int f = 0; f < frames; ++f) {
    auto t0 = Clock::now();
    window->Render();
    window->WaitForCompletion();
    out.cached.push_back(msSince(t0));
    points->Modified();  // the next frame re-builds and re-uploads the vertex buffers
    t0 = Clock::now();
    window->Render();
    window->WaitForCompletion();
    out.upload.push_back(msSince(t0));
  }
  vtkNew<vtkUnsignedCharArray> pixels;
  window->GetRGBACharPixelData(0, 0, int(camera.width) - 1, int(camera.height) - 1, 0, pixels);
  for (vtkIdType i = 0; i < vtkIdType(camera.width) * camera.height; ++i)
    if (pixels->GetValue(4 * i) != 255 || pixels->GetValue(4 * i + 1) != 255) ++out.covered;
  const char* caps = window->ReportCapabilities();
  const std::string report = caps ? caps : "";
  const size_t at = report.find("OpenGL renderer string:");
  if (at != std::string::npos) {
    const size_t begin = report.find_first_not_of(" \t", at + 23);
    out.renderer = report.substr(begin, report.find('\n', begin) - begin);
  }
  return out;
}

/// VTK aborts the process when it cannot open the display: try once in a child process first.
bool vtkUsable() {
  const char* display = std::getenv("DISPLAY");
  if (!display || !*display) return false;
  std::fflush(stdout);
  const pid_t pid = fork();
  if (pid < 0) return false;
  if (pid == 0) {
    const int null = open("/dev/null", O_WRONLY);
    if (null >= 0) {
      dup2(null, 1);
      dup2(null, 2);
    }
    vtkNew<vtkRenderer> renderer;
    vtkNew<vtkRenderWindow> window;
    window->SetOffScreenRendering(1);
    window->AddRenderer(renderer);
    window->SetSize(64, 64);
    window->Render();
    _exit(0);
  }
  int status = 0;
  if (waitpid(pid, &status, 0) != pid) return false;
  return WIFEXITED(status) && WEXITSTATUS(status) == 0;
}
#endif

// ---------------------------------------------------------------------------------------------------------
// Measurement
// ---------------------------------------------------------------------------------------------------------

struct Spread {
  double median = 0, min = 0, max = 0;
};

Spread spreadOf(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return {v[v.size() / 2], v.front(), v.back()};
}

struct Timing {
  Spread total;
  double setup, bin, visibility, accumulate, shade;  // of the median frame
};

Timing timingOf(std::vector<rc::RenderStats> runs) {
  std::sort(runs.begin(), runs.end(), [](auto& a, auto& b) { return a.total_ms < b.total_ms; });
  const rc::RenderStats& m = runs[runs.size() / 2];
  return {{m.total_ms, runs.front().total_ms, runs.back().total_ms},
          m.setup_ms,
          m.bin_ms,
          m.visibility_ms,
          m.accumulate_ms,
          m.shade_ms};
}

Timing medianOf(const rc::SurfelRenderer& renderer, const rc::SurfelCloud& cloud, const rc::Camera& camera,
                rc::RenderImages* images, int frames) {
  std::vector<rc::RenderStats> runs(frames);
  renderer.render(cloud, camera, images);  // warm-up
  for (auto& stats : runs) renderer.render(cloud, camera, images, nullptr, &stats);
  return timingOf(runs);
}

size_t coveredPixels(const std::vector<float>& depth) {
  size_t n = 0;
  for (float z : depth) n += std::isfinite(z) ? 1 : 0;
  return n;
}

/// Pixels inside the analytic silhouette (shrunk by 2 px) without weight, and the largest angle between
/// the normals of neighbouring pixels facing the camera (seams).
void quality(const rc::RenderImages& images, const rc::Camera& camera, double silhouette_px, size_t* holes,
             double* seam) {
  *holes = 0;
  *seam = 0;
  for (uint32_t v = 1; v < images.height; ++v)
    for (uint32_t u = 1; u < images.width; ++u) {
      const size_t p = size_t(v) * images.width + u;
      if (std::hypot(u - camera.cx, v - camera.cy) < silhouette_px - 2 && !(images.weight[p] > 0)) ++*holes;
      for (size_t q : {p - 1, p - images.width}) {
        if (!(images.weight[p] > 0 && images.weight[q] > 0)) continue;
        if (images.normal[p].x() < 0.7f || images.normal[q].x() < 0.7f) continue;  // camera on +x
        *seam = std::max(*seam, double(std::acos(std::min(1.0f, images.normal[p].dot(images.normal[q])))));
      }
    }
}

std::string spreadText(const Spread& s, const char* format = "%.1f") {
  char a[32], b[32], c[32], out[112];
  std::snprintf(a, sizeof(a), format, s.median);
  std::snprintf(b, sizeof(b), format, s.min);
  std::snprintf(c, sizeof(c), format, s.max);
  std::snprintf(out, sizeof(out), "%s (%s-%s)", a, b, c);
  return out;
}

}  // namespace

void exactSilhouettesTable(const rc::Camera& camera, double silhouette_px, int frames) {
  std::printf(
      "\nExact silhouettes vs the filtered footprint (SplatConfig::exact_silhouettes; 100k and 1M surfels, 2 "
      "threads, all outputs, the settings alternated 3 times, median of the medians; silhouette offset: half "
      "the "
      "covered span of the centre row minus the analytic silhouette radius, %.2f px)\n\n",
      silhouette_px);
  std::printf(
      "| surfels | exact_silhouettes | total ms | visibility ms | silhouette offset [px] | holes |\n"
      "|---|---|---|---|---|---|\n");
  for (int count : {100000, 1000000}) {
    const rc::SurfelCloud sphere = sampleSphere(1.0, count);
    std::vector<double> total[2], visibility[2];
    rc::RenderImages images[2];
    for (int round = 0; round < 3; ++round)
      for (int exact = 1; exact >= 0; --exact) {
        rc::SplatConfig config;
        config.threads = 2;
        config.exact_silhouettes = exact != 0;
        const Timing t =
            medianOf(rc::SurfelRenderer(config), sphere, camera, &images[exact], std::min(frames, 5));
        total[exact].push_back(t.total.median);
        visibility[exact].push_back(t.visibility);
      }
    for (int exact = 1; exact >= 0; --exact) {
      size_t holes;
      double seam;
      quality(images[exact], camera, silhouette_px, &holes, &seam);
      // The covered span of the centre row (the sphere's disc is taller than the image).
      const uint32_t row = uint32_t(std::lround(camera.cy));
      int first = -1, last = -1;
      for (uint32_t u = 0; u < images[exact].width; ++u)
        if (images[exact].weight[size_t(row) * images[exact].width + u] > 0) {
          if (first < 0) first = int(u);
          last = int(u);
        }
      const double radius = 0.5 * (last - first + 1);
      auto median = [](std::vector<double> v) {
        std::sort(v.begin(), v.end());
        return v[v.size() / 2];
      };
      std::printf("| %s | %s | %.1f | %.1f | %+.2f | %zu |\n", count == 100000 ? "100k" : "1M",
                  exact ? "on" : "off", median(total[exact]), median(visibility[exact]),
                  radius - silhouette_px, holes);
    }
  }
}

int main(int argc, char** argv) {
  int frames = 9;
  bool quick = false, silhouettes_only = false;  // --silhouettes: the last table alone
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--frames") == 0 && i + 1 < argc) {
      frames = std::max(1, std::atoi(argv[++i]));
    } else if (std::strcmp(argv[i], "--quick") == 0) {
      quick = true;
    } else if (std::strcmp(argv[i], "--silhouettes") == 0) {
      silhouettes_only = true;
    } else {
      std::fprintf(stderr, "usage: %s [--frames N] [--quick] [--silhouettes]\n", argv[0]);
      return 2;
    }
  }
#ifdef RC_BENCH_VTK_PEER
  const bool vtk = vtkUsable();  // before OpenMP starts threads (fork)
#endif
  rc::Camera camera = rc::Camera::perspective(1280, 720, 60.0 * M_PI / 180);
  const double distance = 3.0;
  camera.lookAt(Vec3(distance, 0, 0), Vec3::Zero());
  const double silhouette_px = camera.fx / std::sqrt(distance * distance - 1);
  if (silhouettes_only) {
    exactSilhouettesTable(camera, silhouette_px, frames);
    return 0;
  }
  {
    rc::RenderImages probe;
    rc::RenderStats stats;
    rc::SurfelRenderer(rc::SplatConfig()).render(sampleSphere(1.0, 1000), camera, &probe, nullptr, &stats);
    printMachine(stats.simd_width);
  }
  std::printf(
      "\nEWA splatting, sphere at 1280x720 (silhouette radius %.0f px, %.0f px inside), %d timed frames\n"
      "after a warm-up frame per renderer; times are median (min-max) over the frames. Peers in the same\n"
      "run, their frames interleaved with ours:\n"
      "  SSE2: our renderer with the four-wide passes and scalar set-up (the same image);\n"
      "  plain discs: PlainDiscRasterizer (the projected disc of each surfel, per-pixel plane depth test,\n"
      "  nearest wins; no EWA filter, no blending or normalisation, no fuzzy depth test, flat per-surfel\n"
      "  Lambert shading instead of per-pixel Phong; writes colour + depth; same threads and faces).\n"
      "EWA / plain = EWA median / plain median: what the EWA pipeline costs over plain z-buffered discs\n"
      "(compare the colour+depth rows). Covered px: pixels with a finite depth in each image.\n\n",
      silhouette_px, M_PI * silhouette_px * silhouette_px, frames);
  std::printf(
      "| surfels | threads | EWA | outputs | faces | SIMD | total ms | set-up ms | bin ms | visibility ms "
      "| accumulate ms | shade ms | Msplats/s | fragments/splat | SSE2 ms | speed-up vs SSE2 "
      "| plain discs ms | plain Msplats/s | EWA / plain | covered px EWA / plain |\n"
      "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  struct Variant {
    bool ewa;
    uint32_t outputs;
    bool cull;
  };
  const Variant variants[] = {{true, rc::kOutputAll, false},
                              {false, rc::kOutputAll, false},
                              {true, rc::kOutputColor | rc::kOutputDepth, false},
                              {true, rc::kOutputColor | rc::kOutputDepth, true}};
  std::vector<int> counts = {100000, 1000000};
  if (quick) counts = {100000};
  for (int count : counts) {
    const rc::SurfelCloud cloud = sampleSphere(1.0, count);
    for (int threads : {1, 2})
      for (const Variant& v : variants) {
        rc::SplatConfig config;
        config.threads = threads;
        config.ewa_filter = v.ewa;
        config.outputs = v.outputs;
        config.backface_culling = v.cull;
        const rc::SurfelRenderer renderer(config);
        rc::SplatConfig peer_config = config;
        peer_config.wide_simd = false;
        const rc::SurfelRenderer sse2(peer_config);
        PlainDiscRasterizer plain(threads, v.cull);
        rc::RenderImages images, sse2_images;
        std::vector<rc::Rgba> plain_color;
        std::vector<float> plain_depth;
        renderer.render(cloud, camera, &images);  // warm-ups
        sse2.render(cloud, camera, &sse2_images);
        plain.render(cloud, camera, &plain_color, &plain_depth);
        std::vector<rc::RenderStats> ours(frames), peer(frames);
        std::vector<double> plain_ms;
        for (int f = 0; f < frames; ++f) {  // interleaved: A B C A B C ...
          renderer.render(cloud, camera, &images, nullptr, &ours[f]);
          sse2.render(cloud, camera, &sse2_images, nullptr, &peer[f]);
          const auto t0 = Clock::now();
          plain.render(cloud, camera, &plain_color, &plain_depth);
          plain_ms.push_back(msSince(t0));
        }
        const Timing t = timingOf(ours), p = timingOf(peer);
        const Spread pl = spreadOf(plain_ms);
        rc::RenderStats stats;
        renderer.render(cloud, camera, &images, nullptr, &stats);
        std::printf(
            "| %d | %d | %s | %s | %s | %d-wide | %s | %.1f | %.1f | %.1f | %.1f | %.1f | %s | %.1f | %.1f | "
            "%.2f | %s | %.1f | %.2f | %zu / %zu |\n",
            count, threads, v.ewa ? "on" : "off", v.outputs == rc::kOutputAll ? "all" : "colour+depth",
            v.cull ? "front" : "both", stats.simd_width, spreadText(t.total).c_str(), t.setup, t.bin,
            t.visibility, t.accumulate, t.shade,
            spreadText(
                {count / (t.total.median * 1e3), count / (t.total.max * 1e3), count / (t.total.min * 1e3)})
                .c_str(),
            double(stats.fragments) / stats.splats, p.total.median, p.total.median / t.total.median,
            spreadText(pl).c_str(), count / (pl.median * 1e3), t.total.median / pl.median,
            coveredPixels(images.depth), coveredPixels(plain_depth));
        std::fflush(stdout);
      }
  }

#ifdef RC_BENCH_VTK_PEER
  if (vtk) {
    const char* lp = std::getenv("LP_NUM_THREADS");
    if (!lp) setenv("LP_NUM_THREADS", std::to_string(omp_get_max_threads()).c_str(), 1);
    std::printf(
        "\nOutside peer: VTK %s vtkPointGaussianMapper in an off-screen OpenGL window (X display %s;\n"
        "Mesa llvmpipe without a GPU, LP_NUM_THREADS=%s), same surfels, camera and resolution: every surfel\n"
        "an opaque screen-aligned disc of its world radius (a triangle per point, fragments outside the\n"
        "circle discarded), flat surfel colour, depth of the camera-facing disc, nearest wins. Leaves out:\n"
        "the surfel orientation (normals), EWA filter, blending, shading, back-face culling; the image "
        "stays\n"
        "in OpenGL (no read-back). cached: the vertex buffers of the previous frame are reused; upload: the\n"
        "points are marked modified, so the buffers are rebuilt and uploaded (our renderer reads the cloud\n"
        "in every frame). Render() + WaitForCompletion() (glFinish), median (min-max) of the frames.\n\n",
        vtkVersion::GetVTKVersion(), std::getenv("DISPLAY"), std::getenv("LP_NUM_THREADS"));
    std::printf(
        "| surfels | OpenGL renderer | cached ms | cached Msplats/s | upload ms | upload Msplats/s "
        "| covered px |\n|---|---|---|---|---|---|---|\n");
    for (int count : counts) {
      const rc::SurfelCloud cloud = sampleSphere(1.0, count);
      const VtkTiming vt =
          vtkFrames(cloud, camera, count >= 1000000 ? std::min(frames, 3) : std::min(frames, 5));
      const Spread c = spreadOf(vt.cached), u = spreadOf(vt.upload);
      std::printf("| %d | %s | %s | %.2f | %s | %.2f | %zu |\n", count, vt.renderer.c_str(),
                  spreadText(c).c_str(), count / (c.median * 1e3), spreadText(u).c_str(),
                  count / (u.median * 1e3), vt.covered);
      std::fflush(stdout);
    }
  } else {
    std::printf(
        "\nOutside peer VTK vtkPointGaussianMapper: skipped (no usable X display; run under `xvfb-run -a` to "
        "measure it off-screen with Mesa llvmpipe)\n");
  }
#else
  std::printf("\nOutside peer VTK vtkPointGaussianMapper: skipped (built without PCL/VTK)\n");
#endif

  std::printf(
      "\nDepth tolerance vs quality (100k surfels, 2 threads; holes inside the silhouette, largest "
      "normal angle between neighbouring pixels facing the camera)\n\n");
  std::printf(
      "| depth_tolerance_scale | EWA | total ms | holes | seam angle [rad] |\n|---|---|---|---|---|\n");
  const rc::SurfelCloud cloud = sampleSphere(1.0, 100000);
  for (double scale : {0.0, 0.25, 1.0, 4.0})
    for (bool ewa : {true, false}) {
      rc::SplatConfig config;
      config.threads = 2;
      config.depth_tolerance_scale = scale;
      config.ewa_filter = ewa;
      rc::RenderImages images;
      const Timing t = medianOf(rc::SurfelRenderer(config), cloud, camera, &images, std::min(frames, 5));
      size_t holes;
      double seam;
      quality(images, camera, silhouette_px, &holes, &seam);
      std::printf("| %.2f | %s | %s | %zu | %.4f |\n", scale, ewa ? "on" : "off", spreadText(t.total).c_str(),
                  holes, seam);
    }
  exactSilhouettesTable(camera, silhouette_px, frames);
  std::printf("\nload average at end: %s\n", loadAverage().c_str());
  return 0;
}
