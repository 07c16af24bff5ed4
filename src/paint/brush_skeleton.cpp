#include "relaxed_connectivity/paint/brush_skeleton.h"

#include <Eigen/Eigenvalues>
#include <cmath>
#include <sstream>

namespace rc {

namespace {

constexpr double kPi = 3.14159265358979323846;
/// Contact penalty of the implicit integrator, relative to the spring stiffness: stiff enough that a
/// bristle pressed by its springs stays within a fraction of a millimetre of the plane.
constexpr double kContactStiffness = 1000;

/// Handle points and active masses of a preset in the brush frame (Fig. 5.3); chains[c][k] is the node of
/// segment k (0 = next to the ferrule) of bristle chain c.
struct Layout {
  std::vector<Vec3> handles;
  std::vector<Vec3> actives;
  std::vector<std::vector<int>> chains;         // indices into actives
  std::vector<std::vector<int>> chain_handles;  // handle points each chain hangs from
};

Layout roundLayout(const BrushPreset& p) {
  Layout l;
  l.handles.push_back(Vec3::Zero());
  for (int i = 0; i < p.handle_ring; ++i) {
    const double a = 2 * kPi * i / p.handle_ring;
    l.handles.push_back(Vec3(p.radius * std::cos(a), p.radius * std::sin(a), 0));
  }
  l.handles.push_back(Vec3(0, 0, 0.5 * p.bristle_length));  // apex inside the handle (see flatLayout)
  std::vector<int> all_handles(l.handles.size());
  for (size_t i = 0; i < all_handles.size(); ++i) all_handles[i] = int(i);
  for (int c = 0; c < p.chains; ++c) {
    const double a = 2 * kPi * c / p.chains;
    std::vector<int> chain;
    for (int k = 1; k <= p.segments; ++k) {
      const double s = double(k) / p.segments;
      // One chain runs on the axis; several sit on a ring that narrows towards the tip.
      const double ring = p.chains == 1 ? 0.0 : 0.5 * p.radius * (1.0 - 0.5 * s);
      chain.push_back(int(l.actives.size()));
      l.actives.push_back(Vec3(ring * std::cos(a), ring * std::sin(a), -p.bristle_length * s));
    }
    l.chains.push_back(chain);
    l.chain_handles.push_back(all_handles);
  }
  return l;
}

Layout flatLayout(const BrushPreset& p) {
  Layout l;
  const auto across = [&](int c) {
    return p.chains == 1 ? 0.0 : p.radius * (2.0 * c / (p.chains - 1) - 1.0);
  };
  // Per chain: front and back on the ferrule plane, and an apex inside the handle. Without points off the
  // ferrule plane a bristle mirrored through it would have the same spring lengths: the brush could flip.
  for (int c = 0; c < p.chains; ++c) {
    for (double y : {-0.5 * p.thickness, 0.5 * p.thickness}) l.handles.push_back(Vec3(across(c), y, 0));
    l.handles.push_back(Vec3(across(c), 0, 0.5 * p.bristle_length));
  }
  for (int c = 0; c < p.chains; ++c) {
    std::vector<int> chain, hangs;
    for (int k = 1; k <= p.segments; ++k) {
      chain.push_back(int(l.actives.size()));
      l.actives.push_back(Vec3(across(c), 0, -p.bristle_length * double(k) / p.segments));
    }
    for (int d = std::max(0, c - 1); d <= std::min(p.chains - 1, c + 1); ++d)
      for (int r = 0; r < 3; ++r) hangs.push_back(3 * d + r);
    l.chains.push_back(chain);
    l.chain_handles.push_back(hangs);
  }
  return l;
}

}  // namespace

BrushSkeleton::BrushSkeleton(const BrushPreset& preset) : preset_(preset), mass_(preset.mass) {
  const Layout l = preset.shape == BrushShape::kRound ? roundLayout(preset) : flatLayout(preset);
  handle_count_ = int(l.handles.size());
  rest_ = l.handles;
  rest_.insert(rest_.end(), l.actives.begin(), l.actives.end());
  const auto add = [&](int a, int b) {
    springs_.push_back({a, b, (rest_[a] - rest_[b]).norm(), preset.spring_stiffness, preset.damping});
  };
  const auto node = [&](int active) { return handle_count_ + active; };
  const int chains = int(l.chains.size());
  for (int c = 0; c < chains; ++c) {
    const std::vector<int>& chain = l.chains[c];
    for (size_t k = 0; k < chain.size(); ++k) {
      for (int h : l.chain_handles[c]) add(h, node(chain[k]));  // hangs from the ferrule
      if (k >= 1) add(node(chain[k - 1]), node(chain[k]));      // along the bristle
      if (k >= 2) add(node(chain[k - 2]), node(chain[k]));      // bending
    }
  }
  // Neighbouring chains (around the ring, or across the flat brush) are tied level by level and diagonally.
  const bool closed = preset.shape == BrushShape::kRound && chains > 2;
  for (int c = 0; c + 1 < chains || (closed && c < chains); ++c) {
    const std::vector<int>& a = l.chains[c];
    const std::vector<int>& b = l.chains[(c + 1) % chains];
    for (size_t k = 0; k < a.size(); ++k) {
      add(node(a[k]), node(b[k]));
      if (k + 1 < a.size()) add(node(a[k]), node(b[k + 1])), add(node(b[k]), node(a[k + 1]));
    }
  }
  // The implicit step's envelope: the rows of an active mass start at the lowest-numbered active mass a
  // spring ties it to (chains are numbered one after another, so a flat brush's rows reach back at most 4
  // masses).
  std::vector<int> first_node(static_cast<size_t>(activeCount()));
  for (int a = 0; a < activeCount(); ++a) first_node[size_t(a)] = a;
  for (const BrushSpring& s : springs_) {
    const int a = s.a - handle_count_, b = s.b - handle_count_;
    if (a < 0 || b < 0) continue;
    int& first = first_node[size_t(std::max(a, b))];
    first = std::min(first, std::min(a, b));
  }
  system_.setPattern(first_node);
  reset(Eigen::Isometry3d::Identity());
}

std::vector<Vec3> BrushSkeleton::handleOffsets() const {
  return std::vector<Vec3>(rest_.begin(), rest_.begin() + handle_count_);
}

void BrushSkeleton::reset(const Eigen::Isometry3d& world_T_brush) {
  pose_ = world_T_brush;
  x_.resize(rest_.size());
  for (size_t i = 0; i < rest_.size(); ++i) x_[i] = world_T_brush * rest_[i];
  x_prev_ = x_;
  v_.assign(x_.size(), Vec3::Zero());
  planes_.clear();
  steps_ = 0;
}

Vec3 BrushSkeleton::springForce(const BrushSpring& s, const std::vector<Vec3>& x,
                                const std::vector<Vec3>& v) const {
  // Force on node a. (5.1) with a unit direction: K_s (l - l0) along the spring, plus a dashpot on the
  // rate of change of its length.
  const Vec3 d = x[s.b] - x[s.a];
  const double l = d.norm();
  if (l <= 0) return Vec3::Zero();
  const Vec3 e = d / l;
  return (s.stiffness * (l - s.rest_length) + s.damping * e.dot(v[s.b] - v[s.a])) * e;
}

void BrushSkeleton::step(double dt, const Eigen::Isometry3d& world_T_brush) {
  if (preset_.integrator == BrushIntegrator::kImplicitEuler)
    stepImplicitEuler(dt, world_T_brush);
  else
    stepVerlet(dt, world_T_brush);
  pose_ = world_T_brush;
  last_dt_ = dt;
  ++steps_;
}

void BrushSkeleton::checkActive(int node, double dt, const Eigen::Isometry3d& world_T_brush) const {
  const double max_distance = 10 * preset_.bristle_length;
  const Vec3& x = x_[node];
  if (x.allFinite() && (x - world_T_brush.translation()).squaredNorm() <= max_distance * max_distance) return;
  std::ostringstream why;
  why << "brush skeleton unstable at step " << steps_ + 1 << ": active mass " << node - handle_count_
      << (x.allFinite() ? " ran away (farther than 10 bristle lengths from the handle)" : " is not finite");
  if (preset_.integrator == BrushIntegrator::kVerlet)
    why << "; time step " << dt << " s against the explicit limit " << stepLimit() << " s, or";
  else
    why << "; implicit Euler step " << dt << " s:";
  why << " the device jumped by " << (world_T_brush.translation() - pose_.translation()).norm()
      << " m in one step";
  throw BrushInstability(why.str());
}

void BrushSkeleton::stepVerlet(double dt, const Eigen::Isometry3d& world_T_brush) {
  std::vector<Vec3>& force = force_;
  force.assign(x_.size(), Vec3::Zero());
  for (const BrushSpring& s : springs_) {
    const Vec3 f = springForce(s, x_, v_);
    force[s.a] += f;
    force[s.b] -= f;
  }
  for (int i = 0; i < nodeCount(); ++i) {
    const Vec3 old = x_[i];
    if (isHandle(i)) {
      x_[i] = world_T_brush * rest_[i];
    } else {
      // Verlet: x' = 2x - x_prev + a dt^2.
      x_[i] = 2 * x_[i] - x_prev_[i] + (force[i] / mass_ + preset_.gravity) * dt * dt;
      checkActive(i, dt, world_T_brush);
    }
    x_prev_[i] = old;
    v_[i] = (x_[i] - old) / dt;
  }
}

void BrushSkeleton::stepImplicitEuler(double h, const Eigen::Isometry3d& world_T_brush) {
  // Linearised backward Euler (Baraff and Witkin 1998) over the active masses: v' = v + dv solves
  // (M - h C - h^2 K) dv = h f(x*, v), x' = x* + h dv, with K = df/dx and C = df/dv of the springs (5.1) and
  // dashpots linearised at the predictor x* = x + h v (the handle points already at their new pose). From
  // x* rather than x, a brush carried along at constant velocity is at rest in its frame after one step: the
  // springs' lateral stiffness vanishes at rest length, and a linearisation at x makes them lag.
  for (int i = 0; i < nodeCount(); ++i) {
    const Vec3 next = isHandle(i) ? Vec3(world_T_brush * rest_[i]) : Vec3(x_[i] + h * v_[i]);
    if (isHandle(i)) v_[i] = (next - x_[i]) / h;
    x_prev_[i] = x_[i];
    x_[i] = next;
  }
  const int n = activeCount();
  // Per spring: the block B = h c e e^T + h^2 K with K = k (1 - g) e e^T + k g I (g = max(0, 1 - l0/l), the
  // geometric part dropped for compressed springs so that the system stays positive definite). B adds to
  // the diagonal blocks of its active ends and is subtracted from the off-diagonal block between them: the
  // lower triangle of M - h C - h^2 K within its envelope, which is all the factorisation reads.
  system_.setZero();
  for (int a = 0; a < n; ++a) system_.block(a, a).diagonal().setConstant(mass_);
  rhs_.resize(3 * n);
  for (int a = 0; a < n; ++a) rhs_.segment<3>(3 * a) = h * mass_ * preset_.gravity;
  // The springs' inverse lengths first: independent square roots and divisions pipeline, where one per
  // spring inside the assembly would wait on each other.
  inverse_length_.resize(springs_.size());
  for (size_t k = 0; k < springs_.size(); ++k) {
    const double l = (x_[springs_[k].b] - x_[springs_[k].a]).norm();
    inverse_length_[k] = l > 0 ? 1.0 / l : 0.0;
  }
  const double h2 = h * h;
  for (size_t k = 0; k < springs_.size(); ++k) {
    const BrushSpring& s = springs_[k];
    const double inverse = inverse_length_[k];
    if (inverse == 0) continue;
    const Vec3 e = (x_[s.b] - x_[s.a]) * inverse;
    const double l = 1.0 / inverse;
    const Vec3 f = (s.stiffness * (l - s.rest_length) + s.damping * e.dot(v_[s.b] - v_[s.a])) * e;  // on a
    const double g = std::max(0.0, 1.0 - s.rest_length * inverse);
    const double along = h * s.damping + h2 * s.stiffness * (1.0 - g), across = h2 * s.stiffness * g;
    Eigen::Matrix3d block = along * (e * e.transpose());
    block.diagonal().array() += across;
    const int a = s.a - handle_count_, b = s.b - handle_count_;
    if (a >= 0) system_.block(a, a) += block, rhs_.segment<3>(3 * a) += h * f;
    if (b >= 0) system_.block(b, b) += block, rhs_.segment<3>(3 * b) -= h * f;
    if (a >= 0 && b >= 0) system_.block(std::max(a, b), std::min(a, b)) -= block;
  }
  // Contact planes: f = k_c (n . (p - x)) n, df/dx = -k_c n n^T.
  const double contact = kContactStiffness * preset_.spring_stiffness;
  for (int a = 0; a < n && a < int(planes_.size()); ++a) {
    const ContactPlane& c = planes_[a];
    if (!c.active) continue;
    const double depth = c.normal.dot(c.point - x_[handle_count_ + a]);
    system_.block(a, a) += h2 * contact * (c.normal * c.normal.transpose());
    rhs_.segment<3>(3 * a) += h * contact * depth * c.normal;
  }
  if (!system_.factor()) {
    std::ostringstream why;
    why << "brush skeleton unstable at step " << steps_ + 1
        << ": the implicit Euler system is not positive definite (non-finite spring state)";
    throw BrushInstability(why.str());
  }
  system_.solveInPlace(rhs_.data());
  for (int a = 0; a < n; ++a) {
    const int i = handle_count_ + a;
    v_[i] += rhs_.segment<3>(3 * a);
    x_[i] += h * rhs_.segment<3>(3 * a);
    checkActive(i, h, world_T_brush);
  }
}

void BrushSkeleton::projectActive(int node, const Vec3& position, const Vec3& normal) {
  // (5.5): the mass moves onto the surface; the velocity component into the surface is removed (an
  // inelastic contact), the tangential part is kept by moving the previous position along.
  const Vec3 n = normal.normalized();
  Vec3 v = v_[node];
  const double vn = v.dot(n);
  if (vn < 0) v -= vn * n;
  x_[node] = position;
  x_prev_[node] = position - v * last_dt_;
  v_[node] = v;
}

Vec3 BrushSkeleton::bristleForce() const {
  Vec3 total = Vec3::Zero();
  for (const BrushSpring& s : springs_) {
    const bool a_handle = isHandle(s.a), b_handle = isHandle(s.b);
    if (a_handle == b_handle) continue;
    const Vec3 f = springForce(s, x_, v_);  // on a
    total += a_handle ? f : Vec3(-f);
  }
  return total;
}

double BrushSkeleton::kineticEnergy() const {
  double e = 0;
  for (int i = handle_count_; i < nodeCount(); ++i) e += 0.5 * mass_ * v_[i].squaredNorm();
  return e;
}

double BrushSkeleton::stepLimit() const {
  const int n = activeCount();
  if (n == 0) return std::numeric_limits<double>::infinity();
  Eigen::MatrixXd k = Eigen::MatrixXd::Zero(3 * n, 3 * n), c = k;
  for (const BrushSpring& s : springs_) {
    const Vec3 e = (rest_[s.b] - rest_[s.a]).normalized();
    const Eigen::Matrix3d block = e * e.transpose();
    const int a = s.a - handle_count_, b = s.b - handle_count_;
    for (const auto& [i, j, sign] :
         {std::tuple<int, int, double>{a, a, 1}, {b, b, 1}, {a, b, -1}, {b, a, -1}}) {
      if (i < 0 || j < 0) continue;  // handle points are fixed
      k.block<3, 3>(3 * i, 3 * j) += sign * s.stiffness * block;
      c.block<3, 3>(3 * i, 3 * j) += sign * s.damping * block;
    }
  }
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(k / mass_);
  const double omega2 = eig.eigenvalues().maxCoeff();
  if (omega2 <= 0) return std::numeric_limits<double>::infinity();
  const double omega = std::sqrt(omega2);
  Eigen::Index top;
  eig.eigenvalues().maxCoeff(&top);
  const Eigen::VectorXd mode = eig.eigenvectors().col(top);
  const double zeta = mode.dot(c * mode) / mass_ / (2 * omega);
  return 2.0 / omega * (std::sqrt(1 + zeta * zeta) - zeta);
}

}  // namespace rc
