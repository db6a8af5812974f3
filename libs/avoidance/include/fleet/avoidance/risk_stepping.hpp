#pragma once

#include <string_view>

#include "fleet/avoidance/local_planner.hpp"
#include "fleet/risk/grid.hpp"

namespace fleet::avoidance {

/// RiskLookup over a probability grid through fleet::risk::riskAt (outside the grid: 0).
RiskLookup riskLookup(const risk::ProbabilityGrid& grid);

/// How a reachable candidate is chosen.
enum class SteppingRule {
  /// Thesis §3.2.3 as written: the candidates' collision probabilities are classified into the K
  /// iso-levels of def. 3.6; the step goes to the lowest-risk (highest 1−P) level that holds a
  /// reachable candidate, and progress only ranks the candidates inside that level.
  kIsoLevel,
  /// safety + wProgress · progress over every reachable candidate: enough progress buys a riskier
  /// step. The project's earlier form, kept as a named variant ("risk_stepping_weighted").
  kWeighted,
};

/// "iso_level" / "weighted" (the config's spelling).
std::string_view steppingRuleName(SteppingRule rule);

struct RiskSteppingParams {
  SteppingRule rule = SteppingRule::kIsoLevel;
  int levels = 10;            ///< K of the iso-levels; the risk map service's default K
  double stepTime = 1.0;      ///< the next point is where vMax would take the robot in this time [s]
  int candidates = 25;        ///< points on the reachable arc, spread over ±fan around the target
  double fan = 2.0;           ///< half-angle of the fan [rad]
  int riskSamples = 5;        ///< risk lookups along the segment to each candidate
  double wProgress = 0.3;     ///< kWeighted only: weight of progress against 1 − P
  double minClearance = 0.1;  ///< candidates whose straight segment gets closer than this are unreachable
  double kOmega = 2.0;
  /// The target is the point this far along the path ahead [m], not the path's end: aimed at the
  /// end, a fan of straight steps walks into the shelf between the robot and a goal round a corner.
  double lookahead = 1.0;

  [[nodiscard]] Expected<void> validate() const;
};

struct SteppingChoice {
  Vec2 point;
  double safety = 0.0;  ///< 1 − max P along the segment to the point
  int level = 0;        ///< iso-level (def. 3.6) of that max P
  bool found = false;
};

/// Thesis §3.2.3: each cycle, choose the next point of motion among reachable candidates by
/// params.rule; then steer to it.
class RiskSteppingPlanner final : public LocalPlanner {
 public:
  explicit RiskSteppingPlanner(RiskSteppingParams params = {}) : params_(params) {}
  Command plan(const LocalView& view) override;
  [[nodiscard]] std::string_view name() const override {
    return params_.rule == SteppingRule::kWeighted ? "risk_stepping_weighted" : "risk_stepping";
  }

  [[nodiscard]] SteppingChoice choose(const LocalView& view) const;
  [[nodiscard]] const RiskSteppingParams& params() const { return params_; }

 private:
  RiskSteppingParams params_;
};

}  // namespace fleet::avoidance
