#include "fleet/avoidance/dynamic_window.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "fleet/avoidance/clearance.hpp"
#include "fleet/control/diff_drive_kinematics.hpp"
#include "fleet/core/angles.hpp"

namespace fleet::avoidance {

using control::DiffDriveKinematics;

Expected<void> DwaParams::validate() const {
  if (vSamples < 1 || omegaSamples < 1 || !(simTime > 0.0) || !(clearanceCap > 0.0) || !(lookahead > 0.0) ||
      riskSamples < 1 || discSamples < 1 || wHeading < 0.0 || wClearance < 0.0 || wVelocity < 0.0 ||
      wProgress < 0.0 || wRisk < 0.0) {
    return fleet::unexpected("invalid_dwa_params", "sample counts >= 1, times/distances > 0, weights >= 0");
  }
  return {};
}

Vec2 carrotOnPath(std::span<const Vec2> path, Vec2 robot, double lookahead) {
  if (path.empty())
    return robot;
  if (path.size() == 1)
    return path.front();
  std::size_t best = 0;
  double best_d = std::numeric_limits<double>::infinity();
  double best_s = 0.0;
  for (std::size_t i = 0; i + 1 < path.size(); ++i) {
    const Vec2 ab = path[i + 1] - path[i];
    const double l2 = ab.squaredNorm();
    const double s = l2 > 0.0 ? std::clamp((robot - path[i]).dot(ab) / l2, 0.0, 1.0) : 0.0;
    const double d = fastDistance(path[i] + ab * s, robot);
    if (d < best_d) {
      best_d = d;
      best = i;
      best_s = s;
    }
  }
  double remaining = lookahead;
  Vec2 from = path[best] + (path[best + 1] - path[best]) * best_s;
  for (std::size_t i = best + 1; i < path.size(); ++i) {
    const double seg = fastDistance(from, path[i]);
    if (seg >= remaining)
      return from + (path[i] - from).normalized() * remaining;
    remaining -= seg;
    from = path[i];
  }
  return path.back();
}

void arcPoints(const Pose2& start, Twist tw, double duration, int count, std::vector<Vec2>& out) {
  out.resize(static_cast<std::size_t>(std::max(count, 0)));
  // Interval by interval: each is the same chord (its length ds·sin(dθ/2)/(dθ/2), as
  // integrateExact), along a heading that turns by dθ from one interval to the next, carried as a
  // cosine and sine by that rotation. Three sines and cosines per rollout instead of one per point
  // (profiled at 300 robots, one per point was a tenth of an agent process's time), and no
  // v/ω radius, so nearly straight arcs lose nothing to cancellation.
  const double step = duration / static_cast<double>(std::max(count, 1));
  const double dtheta = tw.omega * step;
  const double half = 0.5 * dtheta;
  const double sinc = std::abs(half) < 1e-9 ? 1.0 - half * half / 6.0 : std::sin(half) / half;
  const double chord = tw.v * step * sinc;
  const double cd = std::cos(dtheta);
  const double sd = std::sin(dtheta);
  double c = std::cos(start.theta + half);
  double s = std::sin(start.theta + half);
  Vec2 p = start.position();
  for (std::size_t k = 0; k < out.size(); ++k) {
    p = p + Vec2{c, s} * chord;
    out[k] = p;
    const double cn = c * cd - s * sd;
    s = s * cd + c * sd;
    c = cn;
  }
}

Command DynamicWindowPlanner::plan(const LocalView& view) {
  const Pose2& pose = view.robot.pose;
  const Vec2 goal = view.goal();
  samples_.clear();
  if (fastDistance(pose.position(), goal) <= view.goalTolerance)
    return {{}, PlanStatus::kGoalReached, false};

  const auto& lim = view.limits;
  const double T = params_.simTime;
  const Twist cur = view.robot.twist;
  // Dynamic window: velocities reachable within one cycle, intersected with the speed bounds.
  const double v_lo = std::max(params_.allowReverse ? lim.vMin : 0.0, cur.v - lim.accelMax * view.dt);
  const double v_hi = std::min(lim.vMax, cur.v + lim.accelMax * view.dt);
  const double w_lo = std::max(-lim.omegaMax, cur.omega - lim.alphaMax * view.dt);
  const double w_hi = std::min(lim.omegaMax, cur.omega + lim.alphaMax * view.dt);

  const Vec2 carrot = carrotOnPath(view.path, pose.position(), params_.lookahead);
  const double carrot_d0 = fastDistance(pose.position(), carrot);
  const double reach = std::max(std::max(lim.vMax, -lim.vMin) * T, params_.clearanceLength) +
                       view.robot.radius + params_.clearanceCap;
  nearbyPoints(view.scan, pose.position(), reach, near_);

  // Progress bookkeeping for the local-minimum escape (towards the goal, which does not move
  // with the robot the way the carrot does).
  const double goal_d = fastDistance(pose.position(), goal);
  if (!(goal == last_goal_) || no_progress_ == 0) {
    best_carrot_distance_ = goal_d;
    last_goal_ = goal;
    no_progress_ = 1;
  } else if (goal_d < best_carrot_distance_ - params_.stuckProgress) {
    best_carrot_distance_ = goal_d;
    no_progress_ = 1;
  } else if (++no_progress_ > params_.stuckCycles && escape_left_ == 0) {
    escape_left_ = params_.escapeCycles;
  }
  const bool escape = escape_left_ > 0;
  if (escape && --escape_left_ == 0)
    no_progress_ = 0;
  const double wHeading = escape ? 0.0 : params_.wHeading;
  const double wProgress = escape ? 0.0 : params_.wProgress;

  // Position on the sample's arc at time t (exact integration, without integrateExact's angle
  // wrapping, which the rollouts do not need).
  const Vec2 p0 = pose.position();
  const double th0 = pose.theta;
  const double c0 = std::cos(th0);
  const double s0 = std::sin(th0);
  auto along = [&](Twist tw, double t) {
    if (std::abs(tw.omega) < 1e-9)
      return p0 + Vec2{c0, s0} * (tw.v * t);
    const double R = tw.v / tw.omega;
    const double th = th0 + tw.omega * t;
    return p0 + Vec2{R * (std::sin(th) - s0), -R * (std::cos(th) - c0)};
  };
  // Only the discs a rollout could come within clearanceCap of: a farther one's clearance is over
  // the cap at every sample, where every use of it (the bound, admissibility, the score) saturates,
  // so leaving it out changes no result (profiled at 300 robots + 150 people: the disc loop over
  // every robot and person in view was the planner's largest own cost).
  const double travel = std::max(std::abs(v_lo), std::abs(v_hi)) * T;
  near_discs_.clear();
  for (const MovingDisc& d : view.discs) {
    const double reachBoth =
        travel + d.velocity.norm() * T + view.robot.radius + d.radius + params_.clearanceCap;
    if (fastDistance(p0, d.position) < reachBoth)
      near_discs_.push_back(d);
  }
  // The disc check's points serve the risk lookups too when their times are among them.
  const int K = params_.discSamples;
  const bool riskOnDiscPoints = K % params_.riskSamples == 0;

  const int nv = params_.vSamples;
  const int nw = params_.omegaSamples;
  const double vmax_abs = std::max(lim.vMax, 1e-9);
  // Pass 1 (cheap): heading, velocity and progress of every sample, and the best score it could
  // still reach (clearance term at its cap, no risk).
  const std::size_t count = static_cast<std::size_t>(nv) * static_cast<std::size_t>(nw);
  samples_.assign(count, DwaSample{});
  upper_.resize(count);
  disc_clr_.resize(count);
  order_.resize(count);
  for (int a = 0; a < nv; ++a) {
    const double v =
        nv == 1 ? v_hi : v_lo + (v_hi - v_lo) * static_cast<double>(a) / static_cast<double>(nv - 1);
    for (int b = 0; b < nw; ++b) {
      const double w = nw == 1 ? 0.5 * (w_lo + w_hi)
                               : w_lo + (w_hi - w_lo) * static_cast<double>(b) / static_cast<double>(nw - 1);
      const std::size_t idx =
          static_cast<std::size_t>(a) * static_cast<std::size_t>(nw) + static_cast<std::size_t>(b);
      DwaSample& s = samples_[idx];
      s.twist = {v, w};
      arcPoints(pose, s.twist, T, K, arc_);
      const Vec2 end_p = arc_.back();
      const Pose2 end{end_p.x, end_p.y, pose.theta + w * T};
      const double goal_bearing = std::atan2(carrot.y - end.y, carrot.x - end.x);
      s.heading = fastDistance(end.position(), carrot) < 1e-6
                      ? 1.0
                      : 1.0 - std::abs(angleDiff(goal_bearing, end.theta)) / kPi;
      s.velocity = std::max(v, 0.0) / vmax_abs;
      s.progress =
          carrot_d0 > 1e-9
              ? std::clamp((carrot_d0 - fastDistance(end.position(), carrot)) / (vmax_abs * T), -1.0, 1.0)
              : 0.0;
      // Discs and risk are cheap next to the scan arcs: compute them here so the bound is tight.
      double clr_discs = std::numeric_limits<double>::infinity();
      for (int k = 1; k <= K && !near_discs_.empty(); ++k) {
        const double t = T * static_cast<double>(k) / static_cast<double>(K);
        const Vec2 p = arc_[static_cast<std::size_t>(k - 1)];
        for (const MovingDisc& d : near_discs_) {
          clr_discs = std::min(clr_discs,
                               fastDistance(p, d.position + d.velocity * t) - view.robot.radius - d.radius);
        }
      }
      disc_clr_[idx] = clr_discs;
      if (view.risk) {
        for (int k = 1; k <= params_.riskSamples; ++k) {
          const double t = T * static_cast<double>(k) / static_cast<double>(params_.riskSamples);
          const Vec2 p = riskOnDiscPoints ? arc_[static_cast<std::size_t>(k * (K / params_.riskSamples) - 1)]
                                          : along(s.twist, t);
          s.risk = std::max(s.risk, view.risk(p));
        }
      }
      // The clearance term can only be lower than the disc clearance alone.
      const double clr_bound = std::clamp(clr_discs, 0.0, params_.clearanceCap) / params_.clearanceCap;
      upper_[idx] = wHeading * s.heading + params_.wClearance * clr_bound + params_.wVelocity * s.velocity +
                    wProgress * s.progress - params_.wRisk * s.risk;
      order_[idx] = idx;
    }
  }
  // Pass 2 (expensive: clearance against the scan and discs, risk) in decreasing order of the
  // bound, stopping once no remaining sample can beat the best. Ties keep the sample that comes
  // first in (v, ω) order, as the exhaustive loop does, so the choice is the same.
  if (params_.prune) {
    std::sort(order_.begin(), order_.end(), [&](std::size_t x, std::size_t y) {
      return upper_[x] != upper_[y] ? upper_[x] > upper_[y] : x < y;
    });
  }
  // Admissible: a rollout keeping minClearance; once the robot is already closer than that (a
  // shelf corner cut, a person who stepped close), one that brings it no closer than it is now —
  // otherwise every sample, turning away included, is inadmissible and the robot can never leave
  // (the safety layer's rule: approaching is forbidden, moving away is allowed).
  double clr_now = arcClearance(pose, Twist{}, 0.0, near_, view.robot.radius, params_.clearanceCap);
  for (const MovingDisc& d : view.discs) {
    clr_now = std::min(clr_now, fastDistance(p0, d.position) - view.robot.radius - d.radius);
  }
  const double admissible_clr = std::min(params_.minClearance, clr_now - 1e-3);
  std::size_t best_idx = count;
  double best_score = -std::numeric_limits<double>::infinity();
  for (const std::size_t idx : order_) {
    if (params_.prune && best_idx < count && upper_[idx] < best_score)
      break;
    DwaSample& s = samples_[idx];
    const double v = s.twist.v;
    const double w = s.twist.omega;
    s.evaluated = true;
    if (params_.prune && disc_clr_[idx] < admissible_clr) {
      // Inadmissible whatever the scan says: it can never be chosen.
      s.evaluated = false;
      continue;
    }
    const double clr = std::min(
        arcClearance(pose, s.twist, T, near_, view.robot.radius, params_.clearanceCap), disc_clr_[idx]);
    s.admissible = clr >= admissible_clr;
    // Fox et al.'s "dist" is the free length of the sample's circular arc, not of the short
    // rollout: score the same curvature over clearanceLength so that, approaching an obstacle,
    // arcs bending away score better long before the straight one becomes inadmissible.
    const double v_eval = std::max(std::abs(v), params_.curvatureSpeedFloor * vmax_abs);
    const double ext = arcClearance(pose, Twist{1.0, w / v_eval}, params_.clearanceLength, near_,
                                    view.robot.radius, params_.clearanceCap);
    const double clr_term = std::min(clr, ext);
    s.clearance = std::clamp(clr_term, 0.0, params_.clearanceCap) / params_.clearanceCap;
    s.score = wHeading * s.heading + params_.wClearance * s.clearance + params_.wVelocity * s.velocity +
              wProgress * s.progress - params_.wRisk * s.risk;
    if (s.admissible && (s.score > best_score || (s.score == best_score && idx < best_idx))) {
      best_score = s.score;
      best_idx = idx;
    }
  }
  DwaSample best;
  if (best_idx < count)
    best = samples_[best_idx];
  if (!best.admissible) {
    // Nothing admissible: brake as hard as the window allows and turn towards the carrot.
    const double turn = angleDiff(std::atan2(carrot.y - pose.y, carrot.x - pose.x), pose.theta);
    return {{std::max(v_lo, 0.0), std::clamp(turn, w_lo, w_hi)}, PlanStatus::kBlocked, false};
  }
  return {best.twist, PlanStatus::kMoving, false};
}

}  // namespace fleet::avoidance
