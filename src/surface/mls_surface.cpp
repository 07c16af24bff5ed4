#include "relaxed_connectivity/surface/mls_surface.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "relaxed_connectivity/core/neighbor_lists.h"
#include "relaxed_connectivity/surface/mls_fits.h"
#include "relaxed_connectivity/surface/normal_estimation.h"

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
  std::vector<uint32_t> ids, local;
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
  const Vec3* nrm;           // null without sample normals
  const uint32_t* to_local;  // cloud index -> index into pos / nrm (null: the same)
  double support;
  Scratch& scratch;

  explicit MlsEvaluator(const MlsSurface& s)
      : MlsEvaluator(s, s.cloud().positions.data(),
                     s.sampleNormals().empty() ? nullptr : s.sampleNormals().data(), nullptr) {}
  /// Over reordered copies of the samples (`local` maps the kd-tree's cloud indices into them).
  MlsEvaluator(const MlsSurface& s, const Vec3* positions, const Vec3* normals, const uint32_t* local)
      : surface(s),
        config(s.config()),
        pos(positions),
        nrm(normals),
        to_local(local),
        support(s.supportRadius()),
        scratch(tl_scratch) {}

  MlsLocalSamples& samples() { return scratch.samples; }

  size_t gatherIds(const Vec3& p, const uint32_t* ids, size_t n, uint32_t extra) {
    return scratch.samples.gather(pos, nrm, ids, n, extra, p, support, config.weight,
                                  config.estimate_normals);
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
    if (!to_local) return gatherIds(p, t.ids.data(), t.ids.size(), MlsLocalSamples::kNoExtra);
    t.local.resize(t.ids.size());
    for (size_t k = 0; k < t.ids.size(); ++k) t.local[k] = to_local[t.ids[k]];
    return gatherIds(p, t.local.data(), t.local.size(), MlsLocalSamples::kNoExtra);
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

/// Order of the points along a grid of cells of size `cell` (x fastest; ties keep the input order), so that
/// the samples of a neighbourhood lie close in memory: a counting sort, or a comparison sort when the grid
/// has many more cells than points. Identity when the grid would not fit 64-bit keys.
void spatialOrder(const std::vector<Vec3>& pos, double cell, std::vector<uint32_t>& order) {
  const size_t n = pos.size();
  order.resize(n);
  for (size_t i = 0; i < n; ++i) order[i] = static_cast<uint32_t>(i);
  Vec3 lo = pos[0], hi = pos[0];
  for (const Vec3& p : pos) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  const Vec3 dims = ((hi - lo) / cell).array().floor() + 1.0;
  if (!(dims.prod() < 1e18)) return;
  const uint64_t nx = static_cast<uint64_t>(dims.x()), ny = static_cast<uint64_t>(dims.y());
  const uint64_t cells = static_cast<uint64_t>(dims.prod());
  std::vector<uint64_t> key(n);
  for (size_t i = 0; i < n; ++i) {
    const Vec3 c = ((pos[i] - lo) / cell).array().floor().cwiseMin(dims.array() - 1.0);
    key[i] = static_cast<uint64_t>(c.x()) +
             nx * (static_cast<uint64_t>(c.y()) + ny * static_cast<uint64_t>(c.z()));
  }
  if (cells <= 4 * static_cast<uint64_t>(n) + 1024) {
    std::vector<uint32_t> start(cells + 1, 0);
    for (uint64_t k : key) ++start[k + 1];
    for (uint64_t c = 0; c < cells; ++c) start[c + 1] += start[c];
    for (size_t i = 0; i < n; ++i) order[start[key[i]]++] = static_cast<uint32_t>(i);
    return;
  }
  std::stable_sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) { return key[a] < key[b]; });
}

}  // namespace

// ----------------------------------------------------------------------------------------------------------------
MlsSurface::MlsSurface(const SurfelCloud& cloud, const MlsConfig& config) : cloud_(cloud), config_(config) {
  cloud.validate();
  if (config.normal_source == MlsNormalSource::kHermite && !cloud.hasNormals() && !cloud.empty() &&
      !config.estimate_normals)
    throw std::invalid_argument("MlsSurface: normal_source=kHermite needs a cloud with normals");
  if (config.fit == MlsFit::kPolynomial && (config.polynomial_degree < 1 || config.polynomial_degree > 3))
    throw std::invalid_argument("MlsSurface: polynomial_degree must be 1, 2 or 3");
  if (!(config.weight.scale > 0) || !std::isfinite(config.weight.scale))
    throw std::invalid_argument("MlsSurface: weight scale (support radius) must be positive and finite");
  if (config.max_iterations < 1) throw std::invalid_argument("MlsSurface: max_iterations must be >= 1");
  if (config.normal_refinement_passes < 0 || config.normal_refinement_passes > 8)
    throw std::invalid_argument("MlsSurface: normal_refinement_passes must be 0..8 (got " +
                                std::to_string(config.normal_refinement_passes) + ")");
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

const std::vector<Vec3>& MlsSurface::sampleNormals() const {
  if (!config_.estimate_normals) return cloud_.normals;
  estimateNormalsOnce(nullptr, nullptr, nullptr);
  return normals_;
}

void MlsSurface::estimateNormalsOnce(const NeighborLists* lists, const std::vector<Vec3>* positions,
                                     const std::vector<uint32_t>* order) const {
  std::call_once(normals_once_, [&] {
    if (cloud_.empty()) return;
    if (!lists) {
      estimatePlaneNormals(cloud_.positions, tree(), config_.weight, support_, config_.min_neighbors,
                           normals_);
      for (int pass = 0; pass < config_.normal_refinement_passes; ++pass)
        refineNormalsBySpheres(cloud_.positions, tree(), config_.weight, support_, config_.min_neighbors,
                               normals_);
      return;
    }
    std::vector<Vec3> local;
    estimatePlaneNormals(*positions, *lists, config_.weight, support_, config_.min_neighbors, local);
    for (int pass = 0; pass < config_.normal_refinement_passes; ++pass)
      refineNormalsBySpheres(*positions, *lists, config_.weight, support_, config_.min_neighbors, local);
    normals_.resize(local.size());
    for (size_t k = 0; k < local.size(); ++k) normals_[(*order)[k]] = local[k];
  });
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
  const size_t n = cloud_.positions.size();
  if (stats) *stats = InputStats();
  for (const Vec3& p : cloud_.positions) {
    if (!p.allFinite()) {
      projectBatch(cloud_.positions, out);
      return;
    }
  }
  out.resize(n);
  if (n == 0) return;
  const bool revisits = config_.max_iterations > 1 || config_.normal_source == MlsNormalSource::kHermite;
  const double margin = revisits ? kListMargin * support_ : 0.0;
  // The samples are processed in a spatial order, as copies: neighbourhood sums then read nearby memory.
  std::vector<uint32_t> order, to_local(n);
  spatialOrder(cloud_.positions, support_ + margin, order);
  std::vector<Vec3> pos(n), nrm;
  for (size_t k = 0; k < n; ++k) {
    pos[k] = cloud_.positions[order[k]];
    to_local[order[k]] = static_cast<uint32_t>(k);
  }
  // Buffers of moderate size are kept per calling thread: page-faulting fresh ones costs as much as the
  // build.
  thread_local std::unique_ptr<NeighborLists> tl_lists;
  std::unique_ptr<NeighborLists> lists_owner =
      tl_lists ? std::move(tl_lists) : std::make_unique<NeighborLists>();
  NeighborLists& lists = *lists_owner;
  NeighborLists::Options options;
  options.num_threads = 0;  // all OpenMP threads
  lists.build(pos, support_ + margin, options);
  if (config_.estimate_normals) estimateNormalsOnce(&lists, &pos, &order);
  const std::vector<Vec3>& normals = sampleNormals();
  if (!normals.empty()) {
    nrm.resize(n);
    for (size_t k = 0; k < n; ++k) nrm[k] = normals[order[k]];
  }
  const double reach2 = margin * margin;
  size_t own = 0, neighbor = 0, tree = 0;
#pragma omp parallel for schedule(dynamic, 256) reduction(+ : own, neighbor, tree)
  for (long k = 0; k < static_cast<long>(n); ++k) {
    const uint32_t i = static_cast<uint32_t>(k);
    MlsEvaluator ev(*this, pos.data(), nrm.empty() ? nullptr : nrm.data(), to_local.data());
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
    out[order[i]] = ev.project(pos[i], gather);
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
