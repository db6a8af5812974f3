#pragma once

#include "fleet/avoidance/local_planner.hpp"

namespace fleet::avoidance {

struct BugParams {
  double followGap = 0.3;        ///< surface gap kept while following a boundary [m]
  double hitGap = 0.35;          ///< an obstacle this close (surface) ahead starts boundary following [m]
  double mlineTolerance = 0.08;  ///< |distance to the m-line| that counts as "on it" [m]
  double leaveMargin = 0.1;      ///< Bug2 leaves only where dist(goal) < dist(H, goal) − margin [m]
  double loopTolerance = 0.25;   ///< back at H (or at L) when closer than this [m]
  double kHeading = 2.0;         ///< ω = k·heading error
  double kGap = 2.0;             ///< steering gain on the gap error while following
  double cruise = 0.3;           ///< forward speed [m/s]

  [[nodiscard]] Expected<void> validate() const;
};

enum class BugVariant { kBug1, kBug2 };
enum class BugMode { kGoToGoal, kFollow, kToLeavePoint, kDone };

/// Lumelsky's Bug1/Bug2 on a point-cloud sensor with a differential-drive body. Boundaries are
/// followed with the obstacle on the robot's right (a fixed turn-left rule).
class BugPlanner final : public LocalPlanner {
 public:
  explicit BugPlanner(BugVariant variant, BugParams params = {}) : variant_(variant), params_(params) {}
  Command plan(const LocalView& view) override;
  [[nodiscard]] std::string_view name() const override {
    return variant_ == BugVariant::kBug1 ? "bug1" : "bug2";
  }
  void reset() override;

  [[nodiscard]] BugMode mode() const { return mode_; }
  [[nodiscard]] int hits() const { return hits_; }
  [[nodiscard]] Vec2 hitPoint() const { return hit_; }

 private:
  Twist steerTowards(const LocalView& view, Vec2 direction) const;
  Twist followBoundary(const LocalView& view) const;
  bool blockedTowards(const LocalView& view, Vec2 direction) const;

  BugVariant variant_;
  BugParams params_;
  BugMode mode_ = BugMode::kGoToGoal;
  bool initialised_ = false;
  Vec2 start_;
  Vec2 goal_;
  Vec2 hit_;
  Vec2 leave_;  ///< Bug1: closest boundary point to the goal seen on the tour
  double leave_goal_distance_ = 0.0;
  double travelled_since_hit_ = 0.0;
  bool left_hit_area_ = false;
  bool toured_ = false;
  Vec2 last_position_;
  int hits_ = 0;
};

}  // namespace fleet::avoidance
