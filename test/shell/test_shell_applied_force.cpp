#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "relaxed_connectivity/shell/shell_applied_force.h"

namespace rc {
namespace {

const std::vector<Vec3> kNodes = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {0, 1, 0}};

std::string messageOf(const Vec3& force, double duration, int node, const Vec3& point, double radius) {
  try {
    shellAppliedForce(force, duration, node, point, radius, kNodes);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

TEST(ShellAppliedForce, NodeByIndexOrByBall) {
  const ShellAppliedForce one = shellAppliedForce(Vec3(0, 0, 2), 0.5, 2, Vec3::Zero(), 0.0, kNodes);
  EXPECT_EQ(one.nodes, (std::vector<size_t>{2}));
  EXPECT_EQ(one.remaining, 0.5);
  EXPECT_EQ(one.force, Vec3(0, 0, 2));
  // The ball includes its boundary (node 1 and node 3 at distance 1 from the origin).
  const ShellAppliedForce ball = shellAppliedForce(Vec3(1, 0, 0), 1.0, -1, Vec3::Zero(), 1.0, kNodes);
  EXPECT_EQ(ball.nodes, (std::vector<size_t>{0, 1, 3}));
}

TEST(ShellAppliedForce, BadRequestsNameTheProblem) {
  const Vec3 f(0, 0, 1), o = Vec3::Zero();
  EXPECT_EQ(messageOf(Vec3(NAN, 0, 0), 1, 0, o, 1), "apply_force: force is not finite");
  EXPECT_EQ(messageOf(Vec3::Zero(), 1, 0, o, 1), "apply_force: force is zero");
  EXPECT_EQ(messageOf(f, 0, 0, o, 1), "apply_force: duration must be finite and > 0 s (got 0.000000)");
  EXPECT_EQ(messageOf(f, 1, 4, o, 1), "apply_force: node 4 is out of range (4 nodes)");
  EXPECT_EQ(messageOf(f, 1, -2, o, 1),
            "apply_force: node must be a node index >= 0 or -1 (nodes near point), got -2");
  EXPECT_EQ(messageOf(f, 1, -1, Vec3(0, INFINITY, 0), 1), "apply_force: point is not finite");
  EXPECT_EQ(messageOf(f, 1, -1, o, -1), "apply_force: radius must be finite and > 0 (got -1.000000)");
  EXPECT_EQ(messageOf(f, 1, -1, Vec3(5, 5, 5), 0.5),
            "apply_force: no node within 0.500000 m of the point (5.000000, 5.000000, 5.000000)");
}

}  // namespace
}  // namespace rc
