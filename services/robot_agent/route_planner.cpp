#include "route_planner.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include "fleet/planning/astar.hpp"
#include "fleet/planning/ompl_planner.hpp"
#include "fleet/planning/wavefront.hpp"

namespace fleet::agent {

Expected<std::unique_ptr<planning::GlobalPlanner>> makeGlobalPlanner(const std::string& kind,
                                                                     planning::CostLayers layers) {
  if (kind == "astar") {
    return std::unique_ptr<planning::GlobalPlanner>(
        std::make_unique<planning::AStarPlanner>(planning::Connectivity::Eight, nullptr, std::move(layers)));
  }
  if (kind == "wavefront") {
    return std::unique_ptr<planning::GlobalPlanner>(std::make_unique<planning::WavefrontPlanner>());
  }
  if (kind == "ompl") {
    planning::OmplOptions oo;
    // Planned inside the agent's cycle: a short budget, and stop at the first path within 20 % of
    // the straight line (the grid is inflated already, so the robot is a point here).
    oo.timeBudget = 0.05;
    oo.simplifyTime = 0.02;
    oo.costThresholdRatio = 1.2;
    return std::unique_ptr<planning::GlobalPlanner>(std::make_unique<planning::OmplPlanner>(oo));
  }
  return unexpected("unknown_planner", "global planner: '" + kind + "' is not astar, wavefront or ompl");
}

bool bodyFits(const planning::OccupancyGrid& raw, Vec2 p, double radius) {
  const auto c = raw.cellAt(p);
  bool fits = c && !raw.blocked(*c);
  for (int k = 0; fits && k < 8; ++k) {
    const double a = k * std::numbers::pi / 4.0;
    const auto e = raw.cellAt(p + Vec2{std::cos(a), std::sin(a)} * radius);
    fits = e && !raw.blocked(*e);
  }
  return fits;
}

void openGoal(planning::OccupancyGrid& g, const planning::OccupancyGrid& raw, Vec2 goal, double radius) {
  if (const auto c = g.cellAt(goal); c && g.blocked(*c) && bodyFits(raw, goal, radius)) {
    g.setBlocked(*c, false);
  }
}

RoutePlanner::RoutePlanner(RouteOptions opt, std::shared_ptr<const planning::OccupancyGrid> grid,
                           std::shared_ptr<const planning::OccupancyGrid> raw)
    : opt_(std::move(opt)), grid_(std::move(grid)), raw_(std::move(raw)) {
  std::string kind = opt_.planner;
  if (opt_.lanes) {
    if (!opt_.lanes->matches(*grid_)) {
      throw std::invalid_argument("lane map was derived from a map of another size");
    }
    ruleLayers_.push_back(std::make_shared<planning::LaneCost>(opt_.lanes));
    kind = "astar";
  }
  if (!opt_.rules.empty()) {
    ruleLayers_.insert(ruleLayers_.end(), opt_.rules.begin(), opt_.rules.end());
    kind = "astar";
  }
  auto made = makeGlobalPlanner(kind, ruleLayers_);
  if (!made) {
    throw std::invalid_argument(made.error().message);
  }
  rules_ = std::move(*made);
  layered_ = kind == "astar";
}

void RoutePlanner::setRisk(std::shared_ptr<const risk::RiskLookup> risk) {
  preferred_.reset();
  if (!risk || !layered_) {
    return;  // wavefront and OMPL plan on the grid alone
  }
  planning::CostLayers layers = ruleLayers_;
  layers.push_back(std::make_shared<planning::EnterCellCost>(
      "risk", [r = std::move(risk), w = opt_.riskWeight, frame = grid_](planning::Cell c) {
        return 1.0 + w * std::clamp(r->at(frame->cellCenter(c)), 0.0, 1.0);
      }));
  preferred_ =
      std::make_unique<planning::AStarPlanner>(planning::Connectivity::Eight, nullptr, std::move(layers));
}

Expected<planning::Path> RoutePlanner::route(const planning::OccupancyGrid& around, Pose2 from, Pose2 to) {
  auto path = (preferred_ ? *preferred_ : *rules_).plan(around, from, to);
  if (!path) {
    planning::OccupancyGrid plain = *grid_;  // boxed in by standing robots: wait them out
    openGoal(plain, *raw_, to.position(), opt_.radius);
    path = rules_->plan(plain, from, to);
  }
  if (!path) {
    path = rules_->plan(*raw_, from, to);  // a start or goal hugging a shelf
  }
  return path;
}

Expected<planning::Path> RoutePlanner::detour(const planning::OccupancyGrid& detour, Pose2 from, Pose2 to) {
  return rules_->plan(detour, from, to);
}

}  // namespace fleet::agent
