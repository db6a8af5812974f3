#pragma once

#include <cmath>
#include <vector>

#include "fleet/avoidance/local_planner.hpp"
#include "fleet/control/diff_drive_kinematics.hpp"
#include "fleet/control/velocity_limits.hpp"

namespace fleet::avoidance::test {

/// Points along a wall segment every `step` metres.
inline std::vector<Vec2> wall(Vec2 a, Vec2 b, double step = 0.05) {
  std::vector<Vec2> out;
  const double len = distance(a, b);
  const int n = std::max(1, static_cast<int>(std::ceil(len / step)));
  for (int i = 0; i <= n; ++i)
    out.push_back(a + (b - a) * (static_cast<double>(i) / static_cast<double>(n)));
  return out;
}

/// Points on a circle (a round static obstacle).
inline std::vector<Vec2> ring(Vec2 c, double r, int n = 64) {
  std::vector<Vec2> out;
  for (int i = 0; i < n; ++i) {
    const double a = 2.0 * 3.14159265358979323846 * static_cast<double>(i) / static_cast<double>(n);
    out.push_back(c + Vec2{r * std::cos(a), r * std::sin(a)});
  }
  return out;
}

struct RunResult {
  bool reached = false;
  double minClearance = 1e9;  ///< surface clearance to the scan points
  int steps = 0;
  int overruled = 0;
  double path_length = 0.0;
  std::vector<Pose2> trace;
};

/// Close the loop on one robot among static points: plan, apply limits, integrate exactly.
inline RunResult drive(LocalPlanner& planner, Pose2 start, std::vector<Vec2> path,
                       const std::vector<Vec2>& scan, int maxSteps, RiskLookup risk = {},
                       double radius = 0.3) {
  RunResult r;
  LocalView v;
  v.robot.pose = start;
  v.robot.radius = radius;
  v.path = path;
  v.scan = scan;
  v.risk = std::move(risk);
  for (int k = 0; k < maxSteps; ++k) {
    const Command c = planner.plan(v);
    if (c.overruled)
      ++r.overruled;
    if (c.status == PlanStatus::kGoalReached) {
      r.reached = true;
      break;
    }
    const auto lt = control::applyLimits(v.limits, c.twist, v.robot.twist, v.dt);
    const Pose2 next = control::DiffDriveKinematics::integrateExact(v.robot.pose, lt.twist, v.dt);
    r.path_length += distance(next.position(), v.robot.pose.position());
    v.robot.pose = next;
    v.robot.twist = lt.twist;
    r.trace.push_back(next);
    for (const Vec2& q : scan)
      r.minClearance = std::min(r.minClearance, distance(q, next.position()) - radius);
    r.steps = k + 1;
  }
  return r;
}

}  // namespace fleet::avoidance::test
