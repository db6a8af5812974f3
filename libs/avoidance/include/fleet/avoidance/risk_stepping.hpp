#pragma once

#include "fleet/avoidance/local_planner.hpp"
#include "fleet/risk/grid.hpp"

namespace fleet::avoidance {

/// RiskLookup over a probability grid through fleet::risk::riskAt (outside the grid: 0).
RiskLookup riskLookup(const risk::ProbabilityGrid& grid);

struct RiskSteppingParams {
  double step_time = 1.0;      ///< the next point is where v_max would take the robot in this time [s]
  int candidates = 25;         ///< points on the reachable arc, spread over ±fan around the goal
  double fan = 2.0;            ///< half-angle of the fan [rad]
  int risk_samples = 5;        ///< risk lookups along the segment to each candidate
  double w_progress = 0.3;     ///< tie-break towards the goal among equally safe candidates
  double min_clearance = 0.1;  ///< candidates whose straight segment gets closer than this are unreachable
  double k_omega = 2.0;

  [[nodiscard]] Expected<void> validate() const;
};

struct SteppingChoice {
  Vec2 point;
  double safety = 0.0;  ///< 1 − max P along the segment to the point
  bool found = false;
};

/// Thesis §3.2.3: each cycle, choose the next point of motion in the lowest-risk (highest 1−P)
/// reachable region, breaking ties towards the goal; then steer to it.
class RiskSteppingPlanner final : public LocalPlanner {
 public:
  explicit RiskSteppingPlanner(RiskSteppingParams params = {}) : params_(params) {}
  Command plan(const LocalView& view) override;
  [[nodiscard]] std::string_view name() const override { return "risk_stepping"; }

  [[nodiscard]] SteppingChoice choose(const LocalView& view) const;

 private:
  RiskSteppingParams params_;
};

}  // namespace fleet::avoidance
