#pragma once

#include <functional>
#include <memory>
#include <span>
#include <string_view>

#include "fleet/control/twist.hpp"
#include "fleet/control/velocity_limits.hpp"
#include "fleet/core/expected.hpp"
#include "fleet/core/pose2.hpp"
#include "fleet/core/vec2.hpp"

namespace fleet::avoidance {

using control::Twist;

/// Another robot or a human, as a disc moving at constant velocity (world frame).
struct MovingDisc {
  Vec2 position;
  Vec2 velocity;
  double radius = 0.4;
};

struct RobotState {
  Pose2 pose;
  Twist twist;  ///< current (measured or last executed) body velocity
  double radius = 0.4;
};

/// Probability of collision in [0, 1] at a world point; empty = no risk information.
using RiskLookup = std::function<double(Vec2)>;

/// Everything a local planner may look at in one control cycle. Non-owning: the caller keeps the
/// spans alive for the duration of plan().
struct LocalView {
  RobotState robot;
  std::span<const Vec2> path;         ///< path ahead (world frame); the last point is the goal
  std::span<const Vec2> scan;         ///< static obstacle points (world frame)
  std::span<const MovingDisc> discs;  ///< other robots and humans
  RiskLookup risk;                    ///< optional
  control::VelocityLimits limits;
  double dt = 0.1;             ///< control cycle [s]
  double goalTolerance = 0.1;  ///< [m]

  [[nodiscard]] Vec2 goal() const { return path.empty() ? robot.pose.position() : path.back(); }
  [[nodiscard]] double riskAt(Vec2 p) const { return risk ? risk(p) : 0.0; }
};

enum class PlanStatus {
  kMoving,
  kGoalReached,
  kStuck,        ///< the planner detected it makes no progress (e.g. potential-field local minimum)
  kUnreachable,  ///< the planner proved the goal unreachable (e.g. Bug circled the obstacle)
  kBlocked,      ///< the safety layer stopped the robot
};

struct Command {
  Twist twist;
  PlanStatus status = PlanStatus::kMoving;
  bool overruled = false;  ///< the safety layer changed the planner's request
};

class LocalPlanner {
 public:
  virtual ~LocalPlanner() = default;
  virtual Command plan(const LocalView& view) = 0;
  [[nodiscard]] virtual std::string_view name() const = 0;
  /// Forget per-goal memory (Bug's hit points, Elastic Strips' strip...).
  virtual void reset() {}
};

/// The planner named in config: "dwa", "potential_field", "bug1", "bug2", "risk_stepping" (thesis
/// §3.2.3 by iso-level), "risk_stepping_weighted" (safety + progress), "elastic_strips",
/// "elastic_strips_bvh", "vo", "vo_keep_right", "orca" (the former sampling "rvo" never resolved a swap and
/// was removed: "orca" is the reciprocal one).
Expected<std::unique_ptr<LocalPlanner>> makePlanner(std::string_view name);

}  // namespace fleet::avoidance
