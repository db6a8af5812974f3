#include "fleet/avoidance/local_planner.hpp"

#include <string>

#include "fleet/avoidance/bug.hpp"
#include "fleet/avoidance/dynamic_window.hpp"
#include "fleet/avoidance/elastic_strips.hpp"
#include "fleet/avoidance/orca.hpp"
#include "fleet/avoidance/potential_field.hpp"
#include "fleet/avoidance/risk_stepping.hpp"
#include "fleet/avoidance/velocity_obstacle.hpp"

namespace fleet::avoidance {

Expected<std::unique_ptr<LocalPlanner>> makePlanner(std::string_view name) {
  using Ptr = std::unique_ptr<LocalPlanner>;
  if (name == "dwa")
    return Ptr(std::make_unique<DynamicWindowPlanner>());
  if (name == "potential_field")
    return Ptr(std::make_unique<PotentialFieldPlanner>());
  if (name == "bug1")
    return Ptr(std::make_unique<BugPlanner>(BugVariant::kBug1));
  if (name == "bug2")
    return Ptr(std::make_unique<BugPlanner>(BugVariant::kBug2));
  if (name == "risk_stepping")
    return Ptr(std::make_unique<RiskSteppingPlanner>());
  if (name == "risk_stepping_weighted") {
    RiskSteppingParams p;
    p.rule = SteppingRule::kWeighted;
    return Ptr(std::make_unique<RiskSteppingPlanner>(p));
  }
  if (name == "elastic_strips")
    return Ptr(std::make_unique<ElasticStripsPlanner>(ElasticVariant::kOriginal));
  if (name == "elastic_strips_bvh")
    return Ptr(std::make_unique<ElasticStripsPlanner>(ElasticVariant::kBvhTwoSided));
  if (name == "vo")
    return Ptr(std::make_unique<VelocityObstaclePlanner>());
  if (name == "orca")
    return Ptr(std::make_unique<OrcaPlanner>());
  if (name == "vo_keep_right") {
    VelocityObstacleParams p;
    p.rightBias = 1.0;
    return Ptr(std::make_unique<VelocityObstaclePlanner>(p));
  }
  return fleet::unexpected("unknown_planner", "no local planner named '" + std::string(name) + "'");
}

}  // namespace fleet::avoidance
