#include "surface/mls_surface.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "core/neighbor_lists.h"
#include "surface/mls_fits.h"

namespace rc {

MlsFit parseMlsFit(const std::string& name) {
  if (name == "plane") return MlsFit::kPlane;
  if (name == "polynomial") return MlsFit::kPolynomial;
  if (name == "sphere") return MlsFit::kSphere;
  throw std::invalid_argument("parseMlsFit: unknown fit '" + name +
                              "' (expected plane, polynomial or sphere)");
}

const char* mlsFitName(MlsFit fit) {
  switch (fit) {
    case MlsFit::kPlane:
      return "plane";
    case MlsFit::kPolynomial:
      return "polynomial";
    case MlsFit::kSphere:
      return "sphere";
  }
  return "?";
}

namespace {

/// project(): the kd-tree is queried at (1 + m) r, and the candidates serve every later evaluation point
/// within m r of the query centre (exactly: they hold every sample within r of it).
constexpr double kTreeMargin = 0.25;
/// projectInputs(): lists at (1 + m) r when points are revisited (iterations, Hermite normals).
constexpr double kListMargin = 0.2;
/// projectInputs() keeps neighbour-list buffers up to this many entries (~32 MB) per calling thread.
constexpr size_t kMaxRetainedListEntries = size_t(1) << 22;

/// Per-thread kd-tree candidates around `center`, keyed by the surface id.
struct TreeCandidates {
  std::vector<Neighbor> hits;
  std::vector<uint32_t> ids;
  Vec3 center = Vec3::Zero();
  bool valid = false;
  uint64_t owner = 0;
};

struct Scratch {
  MlsLocalSamples samples;
  TreeCandidates tree;
};
thread_local Scratch tl_scratch;

/// One projection (the iteration of 3.7 for every fit) with neighbourhoods from a caller-chosen source.
struct MlsEvaluator {
  const MlsSurface& surface;
  const MlsConfig& config;
  const Vec3* pos;
  const Vec3* nrm;  // null when the cloud has no normals
  double support;
  Scratch& scratch;

  explicit MlsEvaluator(const MlsSurface& s)
      : surface(s),
        config(s.config()),
        pos(s.cloud().positions.data()),
        nrm(s.cloud().hasNormals() ? s.cloud().normals.data() : nullptr),
        support(s.supportRadius()),
        scratch(tl_scratch) {}

  MlsLocalSamples& samples() { return scratch.samples; }

  size_t gatherIds(const Vec3& p, const uint32_t* ids, size_t n, uint32_t extra) {
    return scratch.samples.gather(pos, nrm, ids, n, extra, p, support, config.weight);
  }

  size_t gatherTree(const Vec3& p) {
    TreeCandidates& t = scratch.tree;
    const double reach = kTreeMargin * support;
    if (!t.valid || t.owner != surface.id() || !((p - t.center).squaredNorm() <= reach * reach)) {
      surface.tree().radius(p, support * (1 + kTreeMargin), t.hits);
      t.ids.resize(t.hits.size());
      for (size_t k = 0; k < t.hits.size(); ++k) t.ids[k] = t.hits[k].index;
      t.center = p, t.valid = true, t.owner = surface.id();
    }
    return gatherIds(p, t.ids.data(), t.ids.size(), MlsLocalSamples::kNoExtra);
  }

  /// One step from the samples gathered at p: the foot of x on the local fit, and its normal.
  bool step(const Vec3& x, const Vec3& p, Vec3* next, Vec3* normal) {
    const MlsLocalSamples& s = scratch.samples;
    const Vec3 y = (x - p) / support;
    Vec3 foot = Vec3::Zero(), n = Vec3::Zero();
    switch (config.fit) {
      case MlsFit::kPlane: {  // (3.7)
        Vec3 q;
        if (!fitLocalPlane(s, &q, &n)) return false;
        foot = y - n * n.dot(y - q);
        break;
      }
      case MlsFit::kPolynomial: {  // (3.1)-(3.4)
        Vec3 q, N;
        if (!fitLocalPlane(s, &q, &N)) return false;
        const int degree = std::min(3, std::max(1, config.polynomial_degree));
        if (!projectLocalPolynomial(s, q, N, degree, y, &foot, &n)) return false;
        break;
      }
      case MlsFit::kSphere: {
        LocalSphere sphere;
        if (!(nrm ? fitLocalSphereWithNormals(s, &sphere) : fitLocalSpherePoints(s, &sphere))) return false;
        if (!projectLocalSphere(sphere, y, nrm != nullptr, &foot, &n)) return false;
        break;
      }
    }
    *next = p + support * foot;
    *normal = n;
    return true;
  }

  /// The projection of x; gather(p) fills the samples around p and returns their number.
  template <class Gather>
  MlsProjection project(const Vec3& x, Gather&& gather) {
    MlsProjection result;
    result.point = x;
    const size_t min_n = std::max<size_t>(config.min_neighbors, 3);
    const double tol = config.tolerance * support;
    Vec3 p = x, next = x, normal = Vec3::Zero();
    bool converged = false;
    for (int it = 1; it <= config.max_iterations; ++it) {
      if (gather(p) < min_n) return result;
      if (!step(x, p, &next, &normal) || !next.allFinite()) return result;
      const double step_length = (next - p).norm();
      p = next;
      result.iterations = it;
      if (step_length <= tol) {
        converged = true;
        break;
      }
    }
    result.point = p;
    result.normal = normal;
    if (config.normal_source == MlsNormalSource::kHermite) {
      if (gather(p) == 0) return result;
      const Vec3 sum = localNormalSum(scratch.samples);  // (3.8)
      if (!(sum.squaredNorm() > 0)) return result;
      result.normal = sum.normalized();
    }
    result.valid = converged || !config.require_convergence;
    return result;
  }
};

}  // namespace

// ----------------------------------------------------------------------------------------------------------------
MlsSurface::MlsSurface(const SurfelCloud& cloud, const MlsConfig& config) : cloud_(cloud), config_(config) {
  cloud.validate();
  if (config.normal_source == MlsNormalSource::kHermite && !cloud.hasNormals() && !cloud.empty())
    throw std::invalid_argument("MlsSurface: normal_source=kHermite needs a cloud with normals");
  if (config.fit == MlsFit::kPolynomial && (config.polynomial_degree < 1 || config.polynomial_degree > 3))
    throw std::invalid_argument("MlsSurface: polynomial_degree must be 1, 2 or 3");
  if (!(config.weight.scale > 0) || !std::isfinite(config.weight.scale))
    throw std::invalid_argument("MlsSurface: weight scale (support radius) must be positive and finite");
  if (config.max_iterations < 1) throw std::invalid_argument("MlsSurface: max_iterations must be >= 1");
  if (cloud.size() >= std::numeric_limits<uint32_t>::max())
    throw std::invalid_argument("MlsSurface: too many points (" + std::to_string(cloud.size()) + ")");
  static std::atomic<uint64_t> next_id{1};
  id_ = next_id.fetch_add(1);
  support_ = config.weight.support();
  if (!std::isfinite(support_)) support_ = 4 * config.weight.scale;
}

MlsSurface::~MlsSurface() = default;

const KdTree& MlsSurface::tree() const {
  std::call_once(tree_once_, [this] { tree_ = std::make_unique<KdTree>(cloud_.positions); });
  return *tree_;
}

bool MlsSurface::fitPlane(const Vec3& x, Vec3* q, Vec3* n) const {
  if (cloud_.empty() || !x.allFinite()) return false;
  MlsEvaluator ev(*this);
  if (ev.gatherTree(x) < std::max<size_t>(config_.min_neighbors, 3)) return false;
  Vec3 mean;
  if (!fitLocalPlane(ev.samples(), &mean, n)) return false;
  *q = x + support_ * mean;
  return true;
}

MlsProjection MlsSurface::project(const Vec3& x) const {
  if (cloud_.empty() || !x.allFinite()) {
    MlsProjection result;
    result.point = x;
    return result;
  }
  MlsEvaluator ev(*this);
  return ev.project(x, [&](const Vec3& p) { return ev.gatherTree(p); });
}

void MlsSurface::projectBatch(const std::vector<Vec3>& xs, std::vector<MlsProjection>& out) const {
  out.resize(xs.size());
#pragma omp parallel for schedule(dynamic, 64)
  for (long i = 0; i < static_cast<long>(xs.size()); ++i) out[i] = project(xs[i]);
}

void MlsSurface::projectInputs(std::vector<MlsProjection>& out, InputStats* stats) const {
  const std::vector<Vec3>& pos = cloud_.positions;
  const size_t n = pos.size();
  if (stats) *stats = InputStats();
  for (const Vec3& p : pos) {
    if (!p.allFinite()) {
      projectBatch(pos, out);
      return;
    }
  }
  out.resize(n);
  if (n == 0) return;
  const bool revisits = config_.max_iterations > 1 || config_.normal_source == MlsNormalSource::kHermite;
  const double margin = revisits ? kListMargin * support_ : 0.0;
  // Buffers of moderate size are kept per calling thread: page-faulting fresh ones costs as much as the
  // build.
  thread_local std::unique_ptr<NeighborLists> tl_lists;
  std::unique_ptr<NeighborLists> lists_owner =
      tl_lists ? std::move(tl_lists) : std::make_unique<NeighborLists>();
  NeighborLists& lists = *lists_owner;
  NeighborLists::Options options;
  options.num_threads = 0;  // all OpenMP threads
  lists.build(pos, support_ + margin, options);
  const double reach2 = margin * margin;
  size_t own = 0, neighbor = 0, tree = 0;
#pragma omp parallel for schedule(dynamic, 256) reduction(+ : own, neighbor, tree)
  for (long k = 0; k < static_cast<long>(n); ++k) {
    const uint32_t i = static_cast<uint32_t>(k);
    MlsEvaluator ev(*this);
    // The list of input j holds every sample within r of p when |p - x_j| <= margin.
    auto gather = [&](const Vec3& p) -> size_t {
      if ((p - pos[i]).squaredNorm() <= reach2) {
        ++own;
        return ev.gatherIds(p, lists.begin(i), lists.count(i), i);
      }
      uint32_t best = MlsLocalSamples::kNoExtra;
      double best_d2 = reach2;
      for (const uint32_t* j = lists.begin(i); j != lists.end(i); ++j) {
        const double d2 = (p - pos[*j]).squaredNorm();
        if (d2 <= best_d2) best_d2 = d2, best = *j;
      }
      if (best != MlsLocalSamples::kNoExtra) {
        ++neighbor;
        return ev.gatherIds(p, lists.begin(best), lists.count(best), best);
      }
      ++tree;
      return ev.gatherTree(p);
    };
    out[i] = ev.project(pos[i], gather);
  }
  if (stats) stats->own_list = own, stats->neighbor_list = neighbor, stats->tree = tree;
  if (lists.numEntries() <= kMaxRetainedListEntries) tl_lists = std::move(lists_owner);
}

size_t smoothCloud(SurfelCloud& cloud, const MlsConfig& config) {
  if (cloud.empty()) return 0;
  cloud.validate();
  SurfelCloud source;  // the surface is defined by the unmodified samples
  source.positions = cloud.positions;
  source.normals = cloud.normals;
  MlsSurface surface(source, config);
  std::vector<MlsProjection> projected;
  surface.projectInputs(projected);
  size_t failed = 0;
  for (size_t i = 0; i < projected.size(); ++i) {
    if (!projected[i].valid) {
      ++failed;
      continue;
    }
    cloud.positions[i] = projected[i].point;
    if (cloud.hasNormals()) cloud.normals[i] = projected[i].normal;
  }
  return failed;
}

}  // namespace rc
