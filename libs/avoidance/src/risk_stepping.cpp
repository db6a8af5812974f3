#include "fleet/avoidance/risk_stepping.hpp"

#include <algorithm>
#include <cmath>

#include "fleet/avoidance/clearance.hpp"
#include "fleet/avoidance/dynamic_window.hpp"
#include "fleet/core/angles.hpp"
#include "fleet/risk/iso_levels.hpp"
#include "fleet/risk/query.hpp"

namespace fleet::avoidance {

RiskLookup riskLookup(const risk::ProbabilityGrid& grid) {
  return [&grid](Vec2 p) {
    const auto r = risk::riskAt(grid, p);
    return r ? r->risk : 0.0;
  };
}

std::string_view steppingRuleName(SteppingRule rule) {
  return rule == SteppingRule::kWeighted ? "weighted" : "iso_level";
}

Expected<void> RiskSteppingParams::validate() const {
  if (!(stepTime > 0.0) || candidates < 1 || !(fan >= 0.0) || riskSamples < 1 || !(wProgress >= 0.0) ||
      !(minClearance >= 0.0) || !(kOmega > 0.0) || !(lookahead > 0.0) || levels < 1 ||
      levels > risk::kMaxLevels) {
    return fleet::unexpected("invalid_risk_stepping_params",
                             "positive step, counts, gains and lookahead; 1 <= levels <= 255");
  }
  return {};
}

namespace {

struct Candidate {
  Vec2 point;
  double pmax = 0.0;
  int level = 0;
  double progress = 0.0;
};

/// True when a should be chosen over b.
bool better(SteppingRule rule, double wProgress, const Candidate& a, const Candidate& b) {
  if (rule == SteppingRule::kWeighted) {
    return (1.0 - a.pmax) + wProgress * a.progress > (1.0 - b.pmax) + wProgress * b.progress;
  }
  if (a.level != b.level)
    return a.level < b.level;
  if (a.progress != b.progress)
    return a.progress > b.progress;
  // Equal progress happens on symmetric fans; the lower probability inside the level is the
  // thesis's preference carried one step further.
  return a.pmax < b.pmax;
}

}  // namespace

SteppingChoice RiskSteppingPlanner::choose(const LocalView& view) const {
  const Vec2 p = view.robot.pose.position();
  const Vec2 target = carrotOnPath(view.path, p, params_.lookahead);
  const double dg = fastDistance(p, target);
  const double step = std::min(view.limits.vMax * params_.stepTime, dg);
  const double base = std::atan2(target.y - p.y, target.x - p.x);
  const double r = view.robot.radius;
  // Where the robot already is closer than minClearance, accept any candidate that does not get
  // closer still, so it can always leave.
  const double here = arcClearance({p.x, p.y, 0.0}, {0.0, 0.0}, 0.0, view.scan, r, 1.0);
  const double threshold = std::min(params_.minClearance, here - 1e-6);
  Candidate best;
  bool found = false;
  for (int i = 0; i < params_.candidates; ++i) {
    const double frac =
        params_.candidates == 1 ? 0.5 : static_cast<double>(i) / static_cast<double>(params_.candidates - 1);
    const double a = base + params_.fan * (2.0 * frac - 1.0);
    const Vec2 c = p + Vec2{std::cos(a), std::sin(a)} * step;
    // Reachable: the straight move keeps clear of scan points and of discs advanced in time.
    const Pose2 seg_start{p.x, p.y, a};
    double clr = arcClearance(seg_start, {step, 0.0}, 1.0, view.scan, r, 1.0);
    const double t_move = step / std::max(view.limits.vMax, 1e-9);
    for (int k = 0; k <= 4; ++k) {
      const double s = static_cast<double>(k) / 4.0;
      const Vec2 at = p + (c - p) * s;
      for (const MovingDisc& d : view.discs) {
        clr = std::min(clr, fastDistance(at, d.position + d.velocity * (s * t_move)) - r - d.radius);
      }
    }
    if (clr < threshold || clr <= 0.0)
      continue;
    // The robot passes every point of the segment, so the candidate carries the segment's worst P.
    Candidate cand{c, 0.0, 0, (dg - fastDistance(c, target)) / std::max(step, 1e-9)};  // progress in [−1, 1]
    for (int k = 1; k <= params_.riskSamples; ++k) {
      cand.pmax = std::max(cand.pmax, view.riskAt(p + (c - p) * (static_cast<double>(k) /
                                                                 static_cast<double>(params_.riskSamples))));
    }
    cand.level = risk::isoLevel(cand.pmax, params_.levels);
    if (!found || better(params_.rule, params_.wProgress, cand, best)) {
      best = cand;
      found = true;
    }
  }
  if (!found)
    return {};
  return {best.point, 1.0 - best.pmax, best.level, true};
}

Command RiskSteppingPlanner::plan(const LocalView& view) {
  const Vec2 p = view.robot.pose.position();
  if (fastDistance(p, view.goal()) <= view.goalTolerance)
    return {{}, PlanStatus::kGoalReached, false};
  const SteppingChoice c = choose(view);
  if (!c.found)
    return {{}, PlanStatus::kBlocked, false};
  const double err = angleDiff(std::atan2(c.point.y - p.y, c.point.x - p.x), view.robot.pose.theta);
  const double dist = fastDistance(p, c.point);
  const double v = std::min(view.limits.vMax, dist / params_.stepTime) * std::max(0.0, std::cos(err));
  const double w = std::clamp(params_.kOmega * err, -view.limits.omegaMax, view.limits.omegaMax);
  return {{v, w}, PlanStatus::kMoving, false};
}

}  // namespace fleet::avoidance
