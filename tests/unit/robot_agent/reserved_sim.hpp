#pragma once

// The agent in reserved traffic against a small kinematic world (an open 10 m x 10 m floor, or a
// map with a shelf that its range scan sees, the robot's acceleration limits applied to what it
// commands, people where the test puts them), and synthetic releases in place of a traffic
// manager: the harness of reserved_traffic_test.cpp and reserved_rejoin_test.cpp.
//
// RESERVED_TRACE=1 prints the robot's pose, command, speed, mode and node every cycle.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

#include "agent.hpp"
#include "fleet/control/diff_drive_kinematics.hpp"
#include "fleet/control/velocity_limits.hpp"
#include "fleet/geometry/grid_raycast.hpp"

namespace fleet::reserved_test {

constexpr double kDt = 0.1;
constexpr double kSpacing = 0.5;  // m between nodes (the roadmap's lattice)
constexpr double kY = 5.0;        // the robots drive along y = 5 m

/// Node k of the test's lane: x = 1 + 0.5·k on y = 5 (node 0 is where the robot starts).
inline msg::RouteNode lane(int k) {
  return {k, 1.0 + kSpacing * k, kY};
}

inline std::vector<msg::RouteNode> lane(int first, int last) {
  std::vector<msg::RouteNode> b;
  for (int k = first; k <= last; ++k) {
    b.push_back(lane(k));
  }
  return b;
}

inline msg::TrafficRelease release(std::uint32_t seq, std::vector<msg::RouteNode> base, bool atGoal = false,
                                   std::uint32_t epoch = 1, const std::string& robot = "r1") {
  msg::TrafficRelease r;
  r.robot_id = robot;
  r.epoch = epoch;
  r.seq = seq;
  r.base = std::move(base);
  r.ends_at_goal = atGoal;
  return r;
}

/// One robot on an open floor; what it commands goes through its acceleration limits.
struct Sim {
  agent::AgentParams params;
  std::unique_ptr<agent::Agent> agent;
  Pose2 truth;
  control::Twist twist;
  double left = 0.0;
  double right = 0.0;
  std::uint32_t seq = 0;
  int k = 0;
  std::vector<Vec2> people;  // standing still where they are (map frame)
  std::vector<Vec2> parked;  // other robots standing idle where they are (map frame), known by state
  std::vector<msg::TrafficProgress> reports;
  std::vector<double> reportX;  // the robot's true x at each report
  std::vector<msg::TaskStatus> statuses;
  double maxX = -1e9;
  double minToPeople = 1e9;
  /// The map the robot's range scan sees (72 rays round it, noise-free, as the simulator's
  /// default lidar): set by restartAt with a map, none on the open floor.
  std::shared_ptr<const planning::OccupancyGrid> scanned;

  /// `failS`: a task that gets no closer to its next node for this long fails.
  explicit Sim(const std::string& localPlanner = "dwa", double failS = 180.0) {
    params.id = "r1";
    params.progress.failS = failS;
    params.start = {1.0, kY, 0.0};
    params.wheelBase = 0.4;
    params.localPlanner = localPlanner;
    auto grid = std::make_shared<const planning::OccupancyGrid>(40, 40, 0.25, Vec2{0, 0});
    agent = std::make_unique<agent::Agent>(params, grid);
    truth = params.start;
  }

  /// A new agent standing at `start` (on a free floor, or on `grid`).
  void restartAt(Pose2 start, std::shared_ptr<const planning::OccupancyGrid> grid = nullptr) {
    scanned = grid;
    if (!grid) {
      grid = std::make_shared<const planning::OccupancyGrid>(40, 40, 0.25, Vec2{0, 0});
    }
    params.start = start;
    truth = start;
    agent = std::make_unique<agent::Agent>(params, grid);
  }

  [[nodiscard]] double now() const { return k * kDt; }

  agent::AgentOutput step() {
    truth = control::DiffDriveKinematics::integrateExact(truth, twist, kDt);
    left += (twist.v - twist.omega * 0.2) * kDt;
    right += (twist.v + twist.omega * 0.2) * kDt;
    msg::SensorFrame f;
    f.robot_id = "r1";
    f.seq = seq++;
    f.stamp_ns = static_cast<std::int64_t>(k) * 100'000'000;
    f.wheel_totals_valid = true;
    f.wheel_left_total = left;
    f.wheel_right_total = right;
    f.compass_valid = true;
    f.compass = truth.theta;
    f.range_max = 8.0f;
    f.battery = 0.9f;
    if (scanned) {
      constexpr int kRays = 72;
      f.angle_min = static_cast<float>(-M_PI);
      f.angle_increment = static_cast<float>(2.0 * M_PI / kRays);
      for (int i = 0; i < kRays; ++i) {
        const double a = truth.theta - M_PI + 2.0 * M_PI * i / kRays;
        const auto hit = geometry::raycastGrid(scanned->view(), truth.position(), a, f.range_max);
        f.ranges.push_back(hit.hit ? static_cast<float>(hit.range) : f.range_max);
      }
    }
    for (const Vec2& h : people) {
      const Vec2 rel = h - truth.position();
      const double c = std::cos(truth.theta);
      const double s = std::sin(truth.theta);
      f.detections.push_back({msg::SourceKind::Human, static_cast<float>(c * rel.x + s * rel.y),
                              static_cast<float>(-s * rel.x + c * rel.y), 0.25f});
      minToPeople = std::min(minToPeople, rel.norm());
    }
    for (std::size_t i = 0; i < parked.size(); ++i) {
      const Vec2 rel = parked[i] - truth.position();
      const double c = std::cos(truth.theta);
      const double s = std::sin(truth.theta);
      f.detections.push_back({msg::SourceKind::Robot, static_cast<float>(c * rel.x + s * rel.y),
                              static_cast<float>(-s * rel.x + c * rel.y), 0.3f});
      msg::RobotState o;
      o.robot_id = "p" + std::to_string(i + 1);
      o.stamp_ns = static_cast<std::int64_t>(k) * 100'000'000;
      o.pose = {parked[i].x, parked[i].y, M_PI_2};
      o.radius = 0.3f;
      agent->onOtherRobot(o);
    }
    agent->onFrame(f);
    auto out = agent->step(static_cast<std::int64_t>(k) * 100'000'000, kDt);
    ++k;
    twist = control::applyLimits(params.limits, {out.command.v, out.command.w}, twist, kDt).twist;
    maxX = std::max(maxX, truth.x);
    if (std::getenv("RESERVED_TRACE") != nullptr) {
      std::printf("%5.1f x %6.3f y %6.3f th %5.2f cmd %5.2f %5.2f v %5.2f mode %d node %d%s\n", now(),
                  truth.x, truth.y, truth.theta, out.command.v, out.command.w, twist.v,
                  static_cast<int>(out.state.mode), agent->trafficNode(),
                  out.traffic && out.traffic->blocked ? " BLOCKED" : "");
    }
    if (out.traffic) {
      reports.push_back(*out.traffic);
      reportX.push_back(truth.x);
    }
    if (out.status) {
      statuses.push_back(*out.status);
    }
    return out;
  }

  void run(double seconds) {
    const int until = k + static_cast<int>(std::lround(seconds / kDt));
    while (k < until) {
      (void)step();
    }
  }

  [[nodiscard]] std::int32_t lastNode() const { return reports.empty() ? -1 : reports.back().node; }

  [[nodiscard]] bool failed() const {
    return std::any_of(statuses.begin(), statuses.end(),
                       [](const msg::TaskStatus& s) { return s.state == msg::TaskState::Failed; });
  }
};

inline msg::TaskAssignment order(const msg::Goal& goal) {
  msg::TaskAssignment a;
  a.robot_id = "r1";
  a.task_id = "t1";
  a.revision = 1;
  a.goals.push_back(goal);
  return a;
}

/// A pickup at the end of the lane, far beyond anything released in the tests that use it.
inline const msg::Goal kFarPickup{{9.5, kY, M_PI}, "P-9", msg::GoalAction::Load, 2.0};

/// The tests run with each local planner that drives the base.
class ReservedPlanner : public ::testing::TestWithParam<const char*> {};

}  // namespace fleet::reserved_test
