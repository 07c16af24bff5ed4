// The haptic force law (5.6), (5.7): analytic contacts, friction, depth extrapolation, stale fade, input
// checks.
#include <gtest/gtest.h>

#include <cmath>

#include "relaxed_connectivity/paint/haptic_force_law.h"

namespace rc {
namespace {

// Four handle points on a ring of radius 4 mm in the ferrule plane, plus one on the axis.
std::vector<Vec3> ringHandles() {
  return {Vec3(0, 0, 0), Vec3(0.004, 0, 0), Vec3(0, 0.004, 0), Vec3(-0.004, 0, 0), Vec3(0, -0.004, 0)};
}

DeviceState stylusAt(const Vec3& position, const Eigen::Quaterniond& q = Eigen::Quaterniond::Identity()) {
  DeviceState s;
  s.pose.linear() = q.toRotationMatrix();
  s.pose.translation() = position;
  return s;
}

HandleContactState contactOf(int index, double depth, const Vec3& normal, const Vec3& position) {
  HandleContactState h;
  h.index = index;
  h.depth = depth;
  h.normal = normal;
  h.position = position;
  return h;
}

// A horizontal plane z = 0 (object below): every handle point of a stylus at height z has d = -z, N = +z.
ContactParameters planeContact(const HapticForceLaw& law, const DeviceState& device, double kp, double eta) {
  ContactParameters c;
  c.penalty_stiffness = kp;
  c.friction = eta;
  const std::vector<Vec3> offsets = ringHandles();
  for (int i = 0; i < law.handleCount(); ++i) {
    const Vec3 x = device.pose * offsets[size_t(i)];
    if (x.z() < 0) c.handles.push_back(contactOf(i, -x.z(), Vec3::UnitZ(), x));
  }
  return c;
}

TEST(HapticForceLaw, PenaltyIsKpDNForAnAnalyticPlane) {
  for (DepthMode mode : {DepthMode::kConstant, DepthMode::kPlane}) {
    HapticForceLawOptions options;
    options.depth_mode = mode;
    HapticForceLaw law(ringHandles(), options);
    // Tilted stylus 3 mm into the plane: the handle points have different depths.
    const Eigen::Quaterniond tilt(Eigen::AngleAxisd(0.3, Vec3(1, 1, 0).normalized()));
    const DeviceState device = stylusAt(Vec3(0.01, -0.02, -0.003), tilt);
    const ContactParameters c = planeContact(law, device, 400, 2.0);
    ASSERT_EQ(law.check(c), ContactProblem::kNone);
    law.setContact(c, 0.0);
    const HapticForce f = law.evaluate(device, 0.0);
    Vec3 expected_force = Vec3::Zero(), expected_torque = Vec3::Zero();
    for (const HandleContactState& h : c.handles) {
      const Vec3 fi = 400 * h.depth * h.normal;
      expected_force += fi;
      expected_torque += (h.position - device.pose.translation()).cross(fi);
    }
    EXPECT_EQ(f.handles_in_contact, int(c.handles.size()));
    EXPECT_LT((f.wrench.head<3>() - expected_force).norm(), 1e-9);
    EXPECT_LT((f.wrench.tail<3>() - expected_torque).norm(), 1e-9);
    EXPECT_GT(expected_force.z(), 0.5);  // a few newtons, not a trivial zero
  }
}

TEST(HapticForceLaw, FrictionOpposesTangentialVelocityAndVanishesAtZeroDepth) {
  HapticForceLaw law(ringHandles(), HapticForceLawOptions{});
  DeviceState device = stylusAt(Vec3(0, 0, -0.002));
  const ContactParameters c = planeContact(law, device, 400, 2.0);
  law.setContact(c, 0.0);
  device.linear_velocity = Vec3(0.1, -0.05, 0.02);  // the normal part must not cause friction
  const HapticForce f = law.evaluate(device, 0.0);
  const Vec3 penalty = 5 * 400 * 0.002 * Vec3::UnitZ();
  const Vec3 friction = f.wrench.head<3>() - penalty;
  const Vec3 v_t(0.1, -0.05, 0);
  EXPECT_LT((friction - (-5 * 2.0 * 0.002 * v_t)).norm(), 1e-12);
  EXPECT_LT(friction.dot(v_t), 0);
  EXPECT_NEAR(friction.z(), 0, 1e-15);
  // Rotation about the axis moves the ring handle points tangentially: friction torque opposes it.
  device.linear_velocity.setZero();
  device.angular_velocity = Vec3(0, 0, 3.0);
  EXPECT_LT(law.evaluate(device, 0.0).wrench.tail<3>().z(), 0);
  // At zero depth neither penalty nor friction act, whatever the velocity.
  DeviceState touching = stylusAt(Vec3(0, 0, 0));
  touching.linear_velocity = Vec3(0.3, 0.2, 0);
  ContactParameters zero = c;
  for (HandleContactState& h : zero.handles) h.depth = 0;
  law.setContact(zero, 0.0);
  EXPECT_EQ(law.evaluate(touching, 0.0).wrench.norm(), 0.0);
}

TEST(HapticForceLaw, PlaneExtrapolationMatchesTheAnalyticDepth) {
  HapticForceLaw law(ringHandles(), HapticForceLawOptions{});
  const DeviceState at_update = stylusAt(Vec3(0, 0, -0.001));
  law.setContact(planeContact(law, at_update, 400, 0), 0.0);
  // Between updates the stylus moves; the extrapolated depth is the exact depth below the plane.
  for (double z : {-0.004, -0.0025, -0.001, -0.0002}) {
    const Eigen::Quaterniond tilt(Eigen::AngleAxisd(0.1, Vec3::UnitY()));
    const DeviceState now = stylusAt(Vec3(0.003, 0.001, z), tilt);
    double expected_fz = 0;
    for (const Vec3& offset : ringHandles()) expected_fz += 400 * std::max(0.0, -(now.pose * offset).z());
    EXPECT_NEAR(law.evaluate(now, 0.01).wrench[2], expected_fz, 1e-9) << z;
  }
  // Lifted out: no force (and the constant mode would still push).
  EXPECT_EQ(law.evaluate(stylusAt(Vec3(0, 0, 0.001)), 0.01).wrench.norm(), 0.0);
  HapticForceLawOptions constant;
  constant.depth_mode = DepthMode::kConstant;
  HapticForceLaw thesis(ringHandles(), constant);
  thesis.setContact(planeContact(thesis, at_update, 400, 0), 0.0);
  EXPECT_NEAR(thesis.evaluate(stylusAt(Vec3(0, 0, 0.001)), 0.01).wrench[2], 5 * 400 * 0.001, 1e-12);
}

TEST(HapticForceLaw, StaleContactFadesContinuouslyToZero) {
  HapticForceLawOptions options;
  options.stale_timeout = 0.1;
  options.fade_time = 0.05;
  HapticForceLaw law(ringHandles(), options);
  const DeviceState device = stylusAt(Vec3(0, 0, -0.002));
  law.setContact(planeContact(law, device, 400, 0), 0.0);
  const double full = law.evaluate(device, 0.0).wrench[2];
  ASSERT_NEAR(full, 5 * 400 * 0.002, 1e-12);
  const double dt = 1e-3;
  const double bound = full * dt / options.fade_time * (1 + 1e-9);  // linear fade: the largest step per tick
  double previous = full;
  for (int k = 1; k <= 200; ++k) {
    const double fz = law.evaluate(device, k * dt).wrench[2];
    EXPECT_LE(std::abs(fz - previous), bound) << "tick " << k;
    EXPECT_LE(fz, previous + 1e-12);
    if (k * dt <= options.stale_timeout) {
      EXPECT_NEAR(fz, full, 1e-12) << k;
    }
    previous = fz;
  }
  EXPECT_EQ(previous, 0.0);
  EXPECT_EQ(law.fade(0.15 + 1e-9), 0.0);
  EXPECT_NEAR(law.fade(0.125), 0.5, 1e-12);
  // A fresh update restores the force.
  law.setContact(planeContact(law, device, 400, 0), 0.3);
  EXPECT_NEAR(law.evaluate(device, 0.3).wrench[2], full, 1e-12);
}

TEST(HapticForceLaw, BristleForceIsAddedOnlyWhenAsked) {
  HapticForceLawOptions options;
  HapticForceLaw with(ringHandles(), options);
  options.add_bristle_force = false;
  HapticForceLaw without(ringHandles(), options);
  ContactParameters c;
  c.bristle_force = Vec3(0.1, 0.2, 0.3);
  with.setContact(c, 0);
  without.setContact(c, 0);
  EXPECT_EQ(with.evaluate(stylusAt(Vec3::Zero()), 0).wrench.head<3>(), c.bristle_force);
  EXPECT_EQ(without.evaluate(stylusAt(Vec3::Zero()), 0).wrench.norm(), 0.0);
}

TEST(HapticForceLaw, RejectsBadContacts) {
  HapticForceLaw law(ringHandles(), HapticForceLawOptions{});
  ContactParameters good;
  good.penalty_stiffness = 400;
  good.handles.push_back(contactOf(4, 0.001, Vec3::UnitZ(), Vec3::Zero()));
  EXPECT_EQ(law.check(good), ContactProblem::kNone);
  auto with = [&](auto change) {
    ContactParameters c = good;
    change(c);
    return law.check(c);
  };
  EXPECT_EQ(with([](ContactParameters& c) { c.handles[0].index = 5; }), ContactProblem::kUnknownHandle);
  EXPECT_EQ(with([](ContactParameters& c) { c.handles[0].index = -1; }), ContactProblem::kUnknownHandle);
  EXPECT_EQ(with([](ContactParameters& c) { c.handles[0].depth = NAN; }), ContactProblem::kNonFinite);
  EXPECT_EQ(with([](ContactParameters& c) { c.handles[0].position.x() = INFINITY; }),
            ContactProblem::kNonFinite);
  EXPECT_EQ(with([](ContactParameters& c) { c.friction = NAN; }), ContactProblem::kNonFinite);
  EXPECT_EQ(with([](ContactParameters& c) { c.penalty_stiffness = -1; }), ContactProblem::kNegativeConstant);
  EXPECT_EQ(with([](ContactParameters& c) { c.handles[0].depth = -1e-3; }), ContactProblem::kNegativeDepth);
  EXPECT_EQ(with([](ContactParameters& c) { c.handles[0].normal = Vec3(0, 0, 2); }),
            ContactProblem::kNonUnitNormal);
  EXPECT_EQ(with([](ContactParameters& c) { c.handles.push_back(c.handles[0]); }),
            ContactProblem::kDuplicateHandle);
  EXPECT_STREQ(contactProblemName(ContactProblem::kUnknownHandle), "unknown handle point");
  EXPECT_THROW(parseDepthMode("linear"), std::invalid_argument);
  HapticForceLawOptions bad;
  bad.fade_time = 0;
  EXPECT_THROW(HapticForceLaw(ringHandles(), bad), std::invalid_argument);
}

TEST(DeviceVelocityEstimator, BackwardDifferenceOfPoses) {
  DeviceVelocityEstimator estimator;
  const Vec3 v(0.1, -0.2, 0.05), w(0.3, 0.0, -1.2);
  DeviceState s;
  for (int k = 0; k < 5; ++k) {
    const double t = 0.004 * k;
    const Eigen::Quaterniond q(Eigen::AngleAxisd(w.norm() * t, w.normalized()));
    s = estimator.update(t, v * t, q);
  }
  EXPECT_LT((s.linear_velocity - v).norm(), 1e-12);
  EXPECT_LT((s.angular_velocity - w).norm(), 1e-9);
  // Irregular poses (50 us, 950 us apart) with stamps rounded to 1 ns: the 2 ms baseline keeps the error
  // below 1e-6 relative, where a two-pose difference would reach 2e-5.
  DeviceVelocityEstimator irregular;
  for (int k = 0; k < 40; ++k) {
    const double t = 1.0 + (k / 2) * 1e-3 + (k % 2) * 50e-6 + 0.37e-9;
    s = irregular.update(std::round(t * 1e9) * 1e-9, v * t, Eigen::Quaterniond::Identity());
  }
  EXPECT_LT((s.linear_velocity - v).norm(), 1e-6 * v.norm());
  EXPECT_EQ(checkDevicePose(Vec3(0, NAN, 0), Eigen::Quaterniond::Identity()), PoseProblem::kNonFinite);
  EXPECT_EQ(checkDevicePose(Vec3::Zero(), Eigen::Quaterniond(1, 0, 0, 0.1)), PoseProblem::kNonUnitQuaternion);
  EXPECT_EQ(checkDevicePose(Vec3::Zero(), Eigen::Quaterniond(1, 0, 0, 0.001)), PoseProblem::kNone);
}

}  // namespace
}  // namespace rc
