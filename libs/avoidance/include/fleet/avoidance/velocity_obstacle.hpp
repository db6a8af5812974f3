#pragma once

#include "fleet/avoidance/local_planner.hpp"

namespace fleet::avoidance {

/// First time two discs (relative position `rel` = other − self, relative velocity `vel` =
/// v_self − v_other, combined radius R) touch; +inf if never, 0 if they already overlap.
double discTimeToCollision(Vec2 rel, Vec2 vel, double R);

struct VelocityObstacleParams {
  int headings = 24;     ///< candidate directions over the full circle (plus the preferred one)
  int speeds = 5;        ///< candidate speeds in (0, vMax] (plus standing still)
  double wTtc = 1.0;     ///< penalty = wTtc / ttc + |v − v_pref| (van den Berg et al. 2008)
  double horizon = 5.0;  ///< collisions later than this are ignored [s]
  double margin = 0.05;  ///< added to every combined radius [m]
  double kOmega = 2.5;
  /// Cost per m/s of velocity to the left of the preferred one while a conflict is in view: a
  /// shared keep-right convention turns head-on symmetric encounters (circle swap) into a
  /// roundabout instead of a standoff. 0 = the plain baseline.
  double rightBias = 0.0;

  [[nodiscard]] Expected<void> validate() const;
};

/// Sampling velocity-obstacle planner (the comparison baseline): world-frame velocity candidates
/// scored by distance to the preferred velocity (vMax towards the carrot) plus a time-to-collision
/// penalty; the chosen velocity is then tracked as (v, ω).
class VelocityObstaclePlanner final : public LocalPlanner {
 public:
  explicit VelocityObstaclePlanner(VelocityObstacleParams params = {}) : params_(params) {}
  Command plan(const LocalView& view) override;
  [[nodiscard]] std::string_view name() const override {
    return params_.rightBias > 0.0 ? "vo_keep_right" : "vo";
  }

 private:
  VelocityObstacleParams params_;
};

}  // namespace fleet::avoidance
