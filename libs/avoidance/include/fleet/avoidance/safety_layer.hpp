#pragma once

#include "fleet/avoidance/local_planner.hpp"

namespace fleet::avoidance {

/// Zones in the spirit of Nav2's collision monitor, but measured along the motion the command
/// would really produce rather than as fixed polygons.
struct SafetyParams {
  double stopMargin = 0.05;  ///< stop zone: surface clearance [m] the braking profile must keep
  double slowMargin = 0.30;  ///< slow-down zone: clearance [m] along the arc within slowTime
  double slowTime = 1.0;     ///< look-ahead of the slow-down zone [s]
  double slowRatio = 0.5;    ///< |v| cap in the slow-down zone, as a fraction of vMax
  double sampleStep = 0.05;  ///< time step of the profile check [s]
  /// The slow-down zone counts the scan (walls, shelves) as well as the discs. False: only discs
  /// (people, robots), for a robot on a route known to keep clear of the static map (a roadmap
  /// base keeps 0.1 m, inside slowMargin: every aisle was a slow zone). The stop zone always
  /// counts everything.
  bool slowForStatic = true;

  [[nodiscard]] Expected<void> validate() const;
};

struct SafetyResult {
  Twist twist;
  bool overruled = false;        ///< the request was changed (scaled down, slowed, or stopped)
  bool blocked = false;          ///< no forward scaling of the request was safe; the robot is told to stop
  bool slowed = false;           ///< the slow-down zone capped the speed
  double timeToCollision = 0.0;  ///< of the unmodified request at constant velocity (inf = none)
};

/// Every planner's command goes through this: it checks the motion the command produces over one
/// cycle followed by braking at accelMax (so the robot can always still stop), against the scan
/// points and the discs extrapolated at their velocities. Approaching anything closer than
/// stopMargin is forbidden; moving away from it is allowed, so a robot that got too close can
/// still leave.
class SafetyLayer {
 public:
  explicit SafetyLayer(SafetyParams params = {}) : params_(params) {}

  [[nodiscard]] SafetyResult filter(const LocalView& view, Twist request) const;

  /// True when the cycle-then-brake profile of `cmd` never approaches anything inside stopMargin.
  [[nodiscard]] bool profileSafe(const LocalView& view, Twist cmd) const;

  /// First time the robot disc touches an obstacle when `cmd` is held and discs keep their velocity.
  [[nodiscard]] double timeToCollision(const LocalView& view, Twist cmd, double horizon) const;

  [[nodiscard]] const SafetyParams& params() const { return params_; }

 private:
  SafetyParams params_;
};

/// A planner wrapped by the safety layer; what the agent should run.
class SafePlanner final : public LocalPlanner {
 public:
  SafePlanner(std::unique_ptr<LocalPlanner> inner, SafetyParams params = {})
      : inner_(std::move(inner)), safety_(params) {}
  Command plan(const LocalView& view) override;
  [[nodiscard]] std::string_view name() const override { return inner_->name(); }
  void reset() override { inner_->reset(); }
  [[nodiscard]] const SafetyResult& lastSafety() const { return last_; }

 private:
  std::unique_ptr<LocalPlanner> inner_;
  SafetyLayer safety_;
  SafetyResult last_;
};

}  // namespace fleet::avoidance
