#include "fleet/planning/ompl_planner.hpp"
#include "fleet/planning/segment_free.hpp"

#include <ompl/base/MotionValidator.h>
#include <ompl/base/SpaceInformation.h>
#include <ompl/base/objectives/PathLengthOptimizationObjective.h>
#include <ompl/base/spaces/RealVectorStateSpace.h>
#include <ompl/base/spaces/SE2StateSpace.h>
#include <ompl/geometric/PathGeometric.h>
#include <ompl/geometric/SimpleSetup.h>
#include <ompl/geometric/planners/prm/PRMstar.h>
#include <ompl/geometric/planners/rrt/InformedRRTstar.h>
#include <ompl/geometric/planners/rrt/RRTstar.h>
#include <ompl/util/Console.h>
#include <chrono>
#include <cmath>

#include "fleet/geometry/grid_raycast.hpp"

namespace ob = ompl::base;
namespace og = ompl::geometric;

namespace fleet::planning {

namespace {

Vec2 xy(const ob::State* s, OmplSpace space) {
  if (space == OmplSpace::SE2) {
    const auto* st = s->as<ob::SE2StateSpace::StateType>();
    return {st->getX(), st->getY()};
  }
  const auto* st = s->as<ob::RealVectorStateSpace::StateType>();
  return {st->values[0], st->values[1]};
}

class GridMotionValidator : public ob::MotionValidator {
 public:
  GridMotionValidator(const ob::SpaceInformationPtr& si, std::shared_ptr<const OccupancyGrid> grid,
                      OmplSpace space)
      : ob::MotionValidator(si), grid_(std::move(grid)), space_(space) {}
  bool checkMotion(const ob::State* s1, const ob::State* s2) const override {
    const bool ok = segmentFree(*grid_, xy(s1, space_), xy(s2, space_));
    if (!ok) {
      ++invalid_;
    } else {
      ++valid_;
    }
    return ok;
  }
  bool checkMotion(const ob::State* s1, const ob::State* s2,
                   std::pair<ob::State*, double>& lastValid) const override {
    if (checkMotion(s1, s2)) {
      return true;
    }
    // Last valid fraction by bisection on the segment (used by some planners' extensions).
    double lo = 0.0, hi = 1.0;
    const Vec2 a = xy(s1, space_), b = xy(s2, space_);
    for (int k = 0; k < 30; ++k) {
      const double mid = 0.5 * (lo + hi);
      (segmentFree(*grid_, a, a + (b - a) * mid) ? lo : hi) = mid;
    }
    if (lastValid.first != nullptr) {
      si_->getStateSpace()->interpolate(s1, s2, lo, lastValid.first);
    }
    lastValid.second = lo;
    return false;
  }

 private:
  std::shared_ptr<const OccupancyGrid> grid_;
  OmplSpace space_;
};

}  // namespace

OmplPlanner::OmplPlanner(OmplOptions opt) : opt_(opt) {
  ompl::msg::setLogLevel(ompl::msg::LOG_NONE);  // libraries do not print
}

const char* OmplPlanner::name() const {
  switch (opt_.algorithm) {
    case OmplAlgorithm::RRTstar:
      return "ompl-rrtstar";
    case OmplAlgorithm::PRMstar:
      return "ompl-prmstar";
    case OmplAlgorithm::InformedRRTstar:
      break;
  }
  return "ompl-informed-rrtstar";
}

Expected<Path> OmplPlanner::plan(const OccupancyGrid& rawGrid, Pose2 from, Pose2 to) {
  stats_ = {};
  auto grid = std::make_shared<const OccupancyGrid>(rawGrid.inflated(opt_.robotRadius));
  const auto q = resolveQuery(*grid, from, to);
  if (!q) {
    return unexpected(q.error());
  }
  const double x0 = grid->origin().x, y0 = grid->origin().y;
  const double x1 = x0 + grid->width() * grid->resolution(), y1 = y0 + grid->height() * grid->resolution();
  ob::StateSpacePtr space;
  if (opt_.space == OmplSpace::SE2) {
    auto se2 = std::make_shared<ob::SE2StateSpace>();
    ob::RealVectorBounds b(2);
    b.setLow(0, x0);
    b.setHigh(0, x1);
    b.setLow(1, y0);
    b.setHigh(1, y1);
    se2->setBounds(b);
    space = se2;
  } else {
    auto r2 = std::make_shared<ob::RealVectorStateSpace>(2);
    ob::RealVectorBounds b(2);
    b.setLow(0, x0);
    b.setHigh(0, x1);
    b.setLow(1, y0);
    b.setHigh(1, y1);
    r2->setBounds(b);
    space = r2;
  }
  og::SimpleSetup ss(space);
  const auto si = ss.getSpaceInformation();
  const OmplSpace sp = opt_.space;
  ss.setStateValidityChecker([grid, sp](const ob::State* s) {
    const auto c = grid->cellAt(xy(s, sp));
    return c.has_value() && !grid->blocked(*c);
  });
  si->setMotionValidator(std::make_shared<GridMotionValidator>(si, grid, sp));
  ob::ScopedState<> start(space), goal(space);
  if (sp == OmplSpace::SE2) {
    start->as<ob::SE2StateSpace::StateType>()->setXY(from.x, from.y);
    start->as<ob::SE2StateSpace::StateType>()->setYaw(from.theta);
    goal->as<ob::SE2StateSpace::StateType>()->setXY(to.x, to.y);
    goal->as<ob::SE2StateSpace::StateType>()->setYaw(to.theta);
  } else {
    start->as<ob::RealVectorStateSpace::StateType>()->values[0] = from.x;
    start->as<ob::RealVectorStateSpace::StateType>()->values[1] = from.y;
    goal->as<ob::RealVectorStateSpace::StateType>()->values[0] = to.x;
    goal->as<ob::RealVectorStateSpace::StateType>()->values[1] = to.y;
  }
  ss.setStartAndGoalStates(start, goal, 1e-6);
  auto objective = std::make_shared<ob::PathLengthOptimizationObjective>(si);
  const double threshold = opt_.costThresholdRatio > 0.0
                               ? opt_.costThresholdRatio * distance(from.position(), to.position())
                               : opt_.costThreshold;
  objective->setCostThreshold(ob::Cost(threshold > 0.0 ? threshold : 0.0));
  ss.setOptimizationObjective(objective);
  switch (opt_.algorithm) {
    case OmplAlgorithm::RRTstar: {
      auto p = std::make_shared<og::RRTstar>(si);
      if (opt_.range > 0.0) {
        p->setRange(opt_.range);
      }
      ss.setPlanner(p);
      break;
    }
    case OmplAlgorithm::PRMstar:
      ss.setPlanner(std::make_shared<og::PRMstar>(si));
      break;
    case OmplAlgorithm::InformedRRTstar: {
      auto p = std::make_shared<og::InformedRRTstar>(si);
      if (opt_.range > 0.0) {
        p->setRange(opt_.range);
      }
      ss.setPlanner(p);
      break;
    }
  }
  ss.setup();
  const auto t0 = std::chrono::steady_clock::now();
  const ob::PlannerStatus status = ss.solve(opt_.timeBudget);
  stats_.solveSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (status != ob::PlannerStatus::EXACT_SOLUTION) {
    return unexpected("no_solution", std::string(name()) + ": no collision-free path found within " +
                                         std::to_string(opt_.timeBudget) + " s");
  }
  stats_.rawLength = ss.getSolutionPath().length();
  stats_.thresholdMet = threshold > 0.0 && stats_.rawLength <= threshold;
  if (opt_.simplify) {
    ss.simplifySolution(opt_.simplifyTime);
  }
  const og::PathGeometric& pg = ss.getSolutionPath();
  std::vector<Vec2> pts;
  for (std::size_t k = 0; k < pg.getStateCount(); ++k) {
    pts.push_back(xy(pg.getState(k), sp));
  }
  Path path;
  for (std::size_t k = 0; k < pts.size(); ++k) {
    double theta = from.theta;
    if (k + 1 == pts.size()) {
      theta = to.theta;
    } else if (k > 0) {
      theta = std::atan2(pts[k + 1].y - pts[k].y, pts[k + 1].x - pts[k].x);
    }
    path.poses.push_back({pts[k].x, pts[k].y, theta});
  }
  stats_.length = path.length();
  return path;
}

}  // namespace fleet::planning
