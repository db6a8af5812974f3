#pragma once

#include <memory>

#include "fleet/avoidance/bug.hpp"
#include "fleet/avoidance/local_planner.hpp"

namespace fleet::avoidance {

/// F_att = −kAtt·(q − q_goal) (seed 002 eq. 3.6).
Vec2 attractiveForce(Vec2 q, Vec2 goal, double kAtt);

/// Khatib's repulsion, the gradient of U = ½·kRep·(1/ρ − 1/ρ0)²:
/// F = kRep·(1/ρ − 1/ρ0)·(1/ρ²)·(q − q_obs)/ρ for ρ ≤ ρ0, else 0. (The seed's printed eq. 3.8
/// drops the 1/ρ² factor; see docs/algorithms.md.) `rho` is the distance used (surface distance
/// when the robot has a radius); the direction is from q_obs to q.
Vec2 repulsiveForce(Vec2 q, Vec2 q_obs, double rho, double kRep, double rho0);

struct PotentialFieldParams {
  double kAtt = 1.0;
  double kRep = 0.05;
  double rho0 = 1.0;         ///< influence distance [m] (surface distance)
  double attractCap = 2.0;   ///< |F_att| saturates here, so far goals do not drown the repulsion
  double kV = 0.5;           ///< v = min(vMax, kV·|F|)·max(0, cos heading error)
  double kOmega = 2.0;       ///< ω = k_ω·heading error
  double stuckForce = 0.05;  ///< |F| below this (away from the goal) = local minimum
  int stuckCycles = 20;      ///< ... or no progress by stuckProgress over this many cycles
  double stuckProgress = 0.05;
  bool escapeWithBug2 = true;  ///< documented escape: hand over to Bug2 until it leaves the boundary

  [[nodiscard]] Expected<void> validate() const;
};

/// Sum of the attractive force and one repulsive term per scan point and per disc (nearest point of
/// the disc) within rho0, as in the paper (no per-obstacle de-duplication).
Vec2 totalForce(const LocalView& view, const PotentialFieldParams& params);

class PotentialFieldPlanner final : public LocalPlanner {
 public:
  explicit PotentialFieldPlanner(PotentialFieldParams params = {});
  Command plan(const LocalView& view) override;
  [[nodiscard]] std::string_view name() const override { return "potential_field"; }
  void reset() override;

  [[nodiscard]] bool escaping() const { return escaping_; }
  [[nodiscard]] int stuckDetections() const { return stuck_detections_; }

 private:
  PotentialFieldParams params_;
  BugPlanner escape_;
  bool escaping_ = false;
  int stuck_detections_ = 0;
  int no_progress_ = 0;
  double best_goal_distance_ = 0.0;
  bool have_best_ = false;
};

}  // namespace fleet::avoidance
