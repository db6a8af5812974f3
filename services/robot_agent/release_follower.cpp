// Driving what the traffic manager released (see release_follower.hpp).

#include "release_follower.hpp"

#include <algorithm>
#include <cmath>

#include "base_end.hpp"
#include "fleet/core/angles.hpp"
#include "fleet/core/bends.hpp"
#include "fleet/core/clock.hpp"
#include "fleet/core/segment.hpp"
#include "fleet/site/reachability.hpp"

namespace fleet::agent {
namespace {

/// The path follower's carrot distance [m] (its far-field law gives v ≈ kV · kLookahead).
constexpr double kLookahead = 0.5;

/// Within this distance of its goal the robot is there (the reactive docking's tolerance).
constexpr double kAtGoal = 0.15;
/// A base ending this close to the goal ends on it: the last leg docks onto the goal's pose itself.
constexpr double kGoalOnNode = 0.3;
/// Left of the base [m] below which the robot stands at its end.
constexpr double kAtEnd = 0.02;
/// The local planner drives while the robot is this close to the base [m]; further off, the
/// follower steers it back. The roadmap keeps robots apart only near their nodes: a sampling
/// planner swerving round a person would leave them (the stop rule holds the robot instead, and
/// The traffic manager re-plans around the person).
constexpr double kMaxCrossTrack = 0.25;
/// The follower drives the first metre off a station or parking place (the roadmap's straight
/// leg from a dock to its approach node), as in reactive traffic.
constexpr double kLeaveDistance = 1.0;
/// Held by the gate this long [s]: reported blocked ... (At 1 s a robot waiting for a person to
/// walk past was held by the traffic manager, and a held robot on an approach node shuts the
/// approach nodes beside it: the parking row froze one robot at a time. 3 s: 15.0 tasks in 600 s
/// against 10.8, mean of seeds 1-3, 7, 8, docs/benchmarks.md.)
/// (The hold lasts until the robot has moved the progress watch's movedM from where it began.)
constexpr double kBlockedAfterS = 3.0;
/// The local planner sees this much of the base ahead [m]. Given the whole base, a sampling
/// planner measured its progress to the base's end: on a base that bends back (round a corner and
/// back along the next aisle) the robot got no closer to that end for a while, DWA took it for a
/// local minimum and swerved off the base to escape it.
constexpr double kPlannerWindow = 2.0;
// Corners (fleet/core/bends.hpp): base nodes where the way turns by more than bends::kDrivenRound
// (the 45° of a diagonal on the roadmap lattice the planner drives round), or by more than
// bends::kTight where the disc keeps less than bends::kTightClearance of free space. The robot
// drives straight onto the node and turns there on the spot, as the roadmap's turn times assume.
// Left to the local planner or the follower, it rounded a right angle in an arc that cut 0.17 m off
// it (DWA), or turned 0.5 m early (the follower's carrot) at speed and slid off the base while it
// braked; a tight bend rounded swung its outside towards the shelf (a robot leaving a parking row
// came within 0.003 m of a corner, 40 robots).
/// Onto a corner at most this fast [m/s] (it slides a centimetre while it brakes) ...
constexpr double kTurnSpeed = 0.15;
/// ... from this far before it [m] ...
constexpr double kCornerApproach = 0.8;
/// ... until it is this close [m] (then it turns to the next leg).
constexpr double kOnCorner = 0.05;

/// The fastest docking [m/s] on the base's last leg; the stop at the end of the base brakes it onto
/// The goal and the gate's docking gap governs what stands in front of it. (At reactive docking's
/// 0.3 m/s a lone robot drove 5 % of its time at 0.2-0.35 m/s.)
constexpr double kDockSpeed = 0.8;

/// Standing [m/s] (the last command) on a corner node and facing more than kMisaligned [rad] away
/// from the next base node, the robot turns on the spot until it faces it within kAligned. Left to
/// The rotation shim (1 rad/s, done at 0.2 rad off a point 1 m on) or the follower (done at
/// 0.7 rad), it drove off still turning; with DWA at cruise the arc took it to 2 mm of a shelf
/// corner (robot-shelf minimum separation in one of three runs; 0.033-0.05 m in four with the
/// turn, the base build's 0.043-0.098 m). Once per next node and only on a corner: turning to the
/// next node at every standstill fought the planner's or the gate's turn towards the carrot, a
/// limit cycle on the spot (a stall), and made every 180° turn off a station slower.
constexpr double kStanding = 0.05;
constexpr double kMisaligned = 0.2;
constexpr double kAligned = 0.05;

/// Held by a static obstacle for kRejoinAfterS [s], the robot drives back onto the node it last
/// reached before it goes on, when it stands more than kRejoinOff [m] off the roadmap's edge from
/// that node to the next, or more than the reach tolerance (kOffItsNode) off the node. Its
/// straight way from there to the next node is no roadmap edge: from 0.28 m off its node in the
/// gap between two shelves, a robot's way to a parking place's approach passed a shelf corner
/// 0.29 m off (less than its radius) and the stop rule held it for good (2,100 s, and five robots
/// behind it; full stack, seed 3). (Also after 3 s and when its own planner stood it: 104-121
/// rejoins a run of 20 robots, and the one seed of three that was slower did 29 tasks in 600 s
/// instead of 39-42.) Off the edge: a robot that counted its node reached 0.149 m off (0.13 m off
/// the edge) stood below a shelf corner its straight way on passed 0.31 m off, held for good
/// while the rule acted only beyond the reach tolerance (240 s, its task failed; dense check,
/// seed 24). Off the node as well: driving the straight way from a node reached 0.10 m short, a
/// robot comes nearer the edge as it nears the next node, and one stood 0.046 m off the edge, 0.6 m
/// past its node, with a shelf corner 0.05 m from its body (223 s; dense check, seed 29). Within
/// both, it is on its edge just past its node, and going back gains nothing: it stands, reports
/// itself blocked and is planned round (rejoining there, it went back and forth and never said it
/// was blocked; further past its node it still does, every kRejoinAfterS). More than where a rejoin
/// ends (kRejoinEnd), so one rejoin puts it on the edge.
constexpr double kRejoinOff = 0.05;
constexpr double kOffItsNode = 0.15;
/// A rejoin ends within this [m] of the node (BaseEndParams::settleBeyond while rejoining).
constexpr double kRejoinEnd = 0.03;
constexpr double kRejoinAfterS = 10.0;
/// Held that long by a person between its node and the next (which it holds both of), more than
/// kOffItsNode past its node (just past it, it stands there held by the person), the robot
/// backs onto its node and stands there reporting itself blocked for kGiveWayS or until a new
/// release. The person gets room, and the traffic manager may re-plan it (yield_after_s), which it
/// does only for a robot on its node: the node ahead can then go to others. (Two robots stood
/// 0.3 m past their nodes, a person between them, for 2,000 s: 20 robots under load.)
constexpr double kGiveWayS = 15.0;
constexpr const char* kWhyOwnZero = "driving without getting on";
constexpr const char* kWhyStand = "commanded to stand";

/// The gate's stop rule looks this far along the base [m] (more than the stopping distance plus
/// The gap at cruise).
constexpr double kGateRoute = 3.0;

/// The stretch of the polyline `pts` from arc length `from` on, `length` long.
std::vector<Vec2> stretch(const std::vector<Vec2>& pts, double from, double length) {
  std::vector<Vec2> out;
  double s = 0.0;
  for (std::size_t i = 0; i + 1 < pts.size(); ++i) {
    const Vec2 a = pts[i];
    const Vec2 ab = pts[i + 1] - a;
    const double seg = ab.norm();
    if (seg < 1e-9) {
      continue;
    }
    if (s + seg > from) {
      if (out.empty()) {
        out.push_back(a + ab * (std::max(0.0, from - s) / seg));
      }
      if (s + seg >= from + length) {
        out.push_back(a + ab * ((from + length - s) / seg));
        return out;
      }
      out.push_back(pts[i + 1]);
    }
    s += seg;
  }
  if (out.empty()) {
    out.push_back(pts.back());
  }
  return out;
}

control::PathFollowerParams followerParams() {
  control::PathFollowerParams fp;
  fp.lookahead = kLookahead;
  fp.goalToleranceXy = 0.15;
  fp.goalToleranceTheta = 0.25;
  return fp;
}

}  // namespace

ReleaseFollower::ReleaseFollower(FollowerParams params, std::shared_ptr<const planning::OccupancyGrid> raw,
                                 ProgressWatch& progress)
    : p_(params), raw_(std::move(raw)), progress_(progress), follower_(followerParams()) {}

bool ReleaseFollower::baseEndsAtGoal(const std::optional<TaskGoal>& goal) const {
  const auto end = releases_.end();
  return releases_.endsAtGoal() && end && goal && distance(*end, goal->pose.position()) < kGoalOnNode;
}

void ReleaseFollower::atWork() {
  standing_ = {};  // at work, not standing (a charge lasts longer than the log's minute)
  heldSinceNs_ = -1;
  blocked_ = false;
  baseAhead_ = false;
  dockingLeg_ = false;
}

void ReleaseFollower::holdStill() {
  heldSinceNs_ = -1;
  blocked_ = false;
}

void ReleaseFollower::followerTwist(const control::PathFollowerOutput& r, const Pose2& pose, double& v,
                                    double& w) const {
  v = r.cmd.v;
  w = r.cmd.omega;
  if (!r.finalApproach) {
    // The far-field law gives v = kV·ρ·cos α with ρ ≈ the lookahead: scale v so the robot
    // tracks its path at cruise speed. ω keeps the law's gains (scaling it too made the robot
    // weave in the aisles: the loop gain grows with it while the actuation lags a cycle).
    v *= p_.vMax / (kLookahead * control::LyapunovGains{}.kV);
  }
  // Clamp keeping the curvature: a turn limited by ω_max is driven slower, not wider.
  if (std::abs(w) > p_.wMax) {
    v *= p_.wMax / std::abs(w);
    w = std::copysign(p_.wMax, w);
  }
  if (v > p_.vMax || v < -0.3) {
    const double c = std::clamp(v, -0.3, p_.vMax) / v;
    v *= c;
    w *= c;
  }
  // Far off the carrot's bearing: turn in place first, so the robot does not sweep an arc
  // through its neighbours (robots park side by side) or into shelf ends.
  const Vec2 toCarrot = r.target.position() - pose.position();
  const double bearing = angleDiff(std::atan2(toCarrot.y, toCarrot.x), pose.theta);
  if (!r.finalApproach && toCarrot.norm() > 0.05 && std::abs(bearing) > 0.7) {
    v = 0.0;
    w = std::clamp(2.0 * bearing, -p_.wMax, p_.wMax);
  }
}

FollowCommand ReleaseFollower::drive(const FollowCycle& c, DriveStack& stack) {
  FollowCommand cmd;
  double& v = cmd.v;
  double& w = cmd.w;
  msg::RobotMode& mode = cmd.mode;
  const std::int64_t nowNs = c.nowNs;
  standWhy_.clear();
  standByObstacle_ = false;
  const bool personInTheWay = standByPerson_;  // (as of the last cycle: gone once the person is)
  standByPerson_ = false;
  const Pose2 pose = c.pose;
  const Vec2 here = pose.position();
  if (releases_.advance(here)) {
    progress_.newGoal();  // progress is measured to the next node from now on
  }
  const auto& goal = c.goal;
  const bool toGoal = baseEndsAtGoal(goal);
  // Counted on its goal's node (passed beside it, up to ReleaseParams::passLateral off) but not on
  // The goal's pose: the traffic manager takes it as arrived and releases nothing more, so it docks
  // from here, within the node it holds. (Standing there, one robot waited 300 s with a station's
  // line behind it: dense check, seed 2.)
  const bool shortOfGoal = toGoal && !releases_.nodesAhead();
  dockingLeg_ = toGoal && (releases_.onLastLeg() || shortOfGoal);
  bool docking = false;
  baseAhead_ = false;
  v = 0.0;
  w = 0.0;
  // Standing (at the end of the base, on the goal, or with nothing released): waiting on the
  // traffic manager, which is waiting on other robots; nothing holds it up.
  mode = !c.busy ? msg::RobotMode::Idle : msg::RobotMode::Waiting;
  auto standStill = [&](const char* why, RobotActivity doing) {
    standWhy_ = why;
    cmd.doing = doing;
    aligning_ = false;
    v = 0.0;
    w = 0.0;
    heldSinceNs_ = -1;
    // Backing onto its node for a person and standing there is still being blocked: a flag that
    // dropped meanwhile would have the traffic manager plan it as free for those seconds.
    blocked_ = givingWay();
  };
  // On its goal once it stands there: docking at speed, it used to start its dwell still rolling (a
  // robot reported charging 0.4 s before it stopped on the charger, which charges only a standing
  // robot); it brakes onto the goal at the end of its base.
  if (toGoal && distance(here, goal->pose.position()) < kAtGoal && std::abs(c.lastV) < kStanding) {
    standStill("on its goal", RobotActivity::TurningDocking);
    dockingLeg_ = false;
    cmd.onGoal = true;
    return cmd;
  }
  // On the node where the way it follows turned back: the rest of the base from there.
  const bool pastTurnBack = turnsBackAt_ && releases_.node() == *turnsBackAt_;
  // Off its node and held by a static obstacle: back to the node first, then along the roadmap's
  // edge, which clears the shelves. Held by a person: back to the node, and give way (kGiveWayS).
  const auto own = releases_.at();
  const auto onward = releases_.next();
  const double off = own ? distance(here, *own) : 0.0;
  const double offEdge = own && onward ? pointSegmentDistance(here, *own, *onward) : off;
  const bool rejoin = !rejoining_ && releases_.nodesAhead() && own && standing_.sinceNs >= 0 &&
                      nsToSec(nowNs - standing_.sinceNs) > kRejoinAfterS &&
                      ((standing_.byObstacle && (offEdge > kRejoinOff || off > kOffItsNode)) ||
                       (personInTheWay && off > kOffItsNode));
  if (rejoined_ && rejoinForPerson_) {
    // Back on its node: it stands there, and the base from there afterwards.
    rejoinForPerson_ = false;
    rejoined_ = false;
    givingWayUntilNs_ = nowNs + secToNs(kGiveWayS);
    givingWayRevision_ = releases_.revision();
    followedRevision_ = 0;
  }
  if (givingWayUntilNs_ >= 0 && (nowNs >= givingWayUntilNs_ || givingWayRevision_ != releases_.revision())) {
    givingWayUntilNs_ = -1;
  }
  if (givingWayUntilNs_ >= 0) {
    standStill("giving way to a person", RobotActivity::HeldByPerson);
    return cmd;
  }
  const bool newRelease = followedRevision_ != releases_.revision() || !follower_.hasPath() || pastTurnBack ||
                          rejoin || rejoined_;
  if (!releases_.nodesAhead() && newRelease && !shortOfGoal) {
    rejoinForPerson_ = false;  // (nothing to back along: not giving way)
    standStill("nothing released beyond its node", RobotActivity::WaitingOnRobot);
    return cmd;
  }
  if (newRelease) {
    auto way = shortOfGoal ? ReleaseTracker::Way{{here, goal->pose.position()}, std::nullopt}
                           : releases_.aheadToTurnBack(here);
    std::vector<Vec2> pts = std::move(way.points);
    turnsBackAt_ = way.turnsBackAt;
    rejoining_ = rejoin;
    rejoinForPerson_ = rejoin && personInTheWay;  // (a new release during a rejoin ends it)
    if (rejoined_) {
      aligning_ = true;  // back on its node: face the next one on the spot, then drive the edge
    }
    rejoined_ = false;
    if (rejoining_) {
      pts = {here, *own};
      turnsBackAt_.reset();
      ++rejoins_;
    } else if (toGoal && !turnsBackAt_) {
      pts.back() = goal->pose.position();  // dock on the goal's pose itself
    }
    const Vec2 last = pts.back() - pts[pts.size() - 2];
    const double heading = last.norm() > 1e-6 ? std::atan2(last.y, last.x) : pose.theta;
    if (!follower_.setPath(pts, heading)) {
      standStill("the base is no path to follow", RobotActivity::HeldBySafety);
      return cmd;
    }
    basePath_ = pts;
    followedRevision_ = releases_.revision();
    progress_.newGoal();
    // (The local planner is not reset: an extension continues the path it is driving.)
  }
  const auto r = follower_.step(pose);
  if (!r) {
    standStill("no pose estimate to follow the base with", RobotActivity::HeldBySafety);
    return cmd;
  }
  double left = follower_.pathLength() - r->progress;
  const Vec2 toEnd = basePath_.back() - here;
  const Vec2 facing{std::cos(pose.theta), std::sin(pose.theta)};
  // Rejoining, its node may be behind it within the reach tolerance: it drives onto it all the
  // same (counting it reached there stood it in the rejoin it began, every cycle).
  const BaseEnd end =
      baseEnd(left, toEnd, facing, r->finalApproach,
              rejoining_ ? BaseEndParams{.atEnd = kAtEnd, .settleBeyond = kRejoinEnd, .behindWithin = kAtEnd}
                         : BaseEndParams{.atEnd = kAtEnd, .behindWithin = kAtGoal});
  const bool settling = end == BaseEnd::kSettle;
  if (settling) {
    left = toEnd.norm();  // what the stop at the end brakes for
  }
  if (end == BaseEnd::kStand) {
    if (rejoining_) {
      rejoining_ = false;
      rejoined_ = true;  // back on its node: the base from here next cycle
    }
    standStill("at the end of its base", RobotActivity::WaitingOnRobot);
    return cmd;
  }
  baseAhead_ = true;
  docking = dockingLeg_ && r->finalApproach && !rejoining_;
  if (undockFrom_ && distance(here, *undockFrom_) > kLeaveDistance) {
    undockFrom_.reset();
  }
  const auto turn = releases_.nextTurn(bends::kDrivenRound, bends::kTight, [&](Vec2 at) {
    return raw_ && !site::discFits(*raw_, at, p_.radius + bends::kTightClearance);
  });
  // (Not while rejoining: the corner is on the base beyond the node it drives back to.)
  const bool cornering = !settling && !rejoining_ && turn && turn->distance < kCornerApproach &&
                         distance(here, turn->at) > kOnCorner;
  const bool planning = stack.hasPlanner() && !r->finalApproach && !cornering && !settling && !undockFrom_ &&
                        r->crossTrack < kMaxCrossTrack && !progress_.followerDrives(nowNs);
  bool localBlocked = false;
  if (planning) {
    const auto tw = stack.planLocal(stretch(basePath_, r->progress, kPlannerWindow), localBlocked);
    v = tw.v;
    w = tw.omega;
  } else if (r->finalApproach || cornering || settling) {
    // Onto the corner, or the last stretch: face it and drive straight there (onto a station:
    // only once it faces it). The pose law's curve could bulge off the base.
    // (Turning on the spot only when far off: told to at speed, the robot slides on while it brakes.)
    if (cornering) {
      cornerAt_ = turn->at;
    }
    const Vec2 to = cornering ? turn->at - here : toEnd;
    const double b = angleDiff(std::atan2(to.y, to.x), pose.theta);
    w = std::clamp(2.0 * b, -p_.wMax, p_.wMax);
    if (settling) {
      v = std::abs(b) > 0.25 ? 0.0 : kTurnSpeed;  // the last centimetres, straight and slow
    } else if (docking) {
      // As fast as it can brake onto the station (the cap below; the gate's docking gap still
      // governs what is in front of it).
      v = std::abs(b) > 0.25 ? 0.0 : std::min(kDockSpeed, p_.vMax);
    } else {
      v = std::abs(b) > 0.7 ? 0.0 : p_.vMax;
    }
  } else {
    followerTwist(*r, pose, v, w);
  }
  v = std::max(v, 0.0);  // never backwards off the base
  const auto next = releases_.next();
  const bool alignedThere = next && alignedTo_ && distance(*next, *alignedTo_) < 1e-6;
  const bool onCorner = cornerAt_ && distance(here, *cornerAt_) < kAtGoal;
  if (next && (aligning_ || (std::abs(c.lastV) < kStanding && !alignedThere && onCorner))) {
    const Vec2 to = *next - here;
    const double e = angleDiff(std::atan2(to.y, to.x), pose.theta);
    aligning_ = to.norm() > 0.1 && std::abs(e) > (aligning_ ? kAligned : kMisaligned);
    if (!aligning_) {
      alignedTo_ = next;
    } else {
      // As fast as it can turn and still brake (at half its angular acceleration: a cycle's lag).
      v = 0.0;
      w = std::copysign(std::min(p_.wMax, std::sqrt(p_.limits.alphaMax * std::abs(e))), e);
    }
  } else {
    aligning_ = false;
  }
  // Stop at the end of the base: no faster than the robot can brake from within what is left,
  // one control period late. (An extension in time lifts the limit before it bites.)
  double cap = stoppingSpeed(left, p_.limits.accelMax, c.dt);
  if (turn) {
    // Down to the turning speed by the time it is on the corner (kOnCorner, with as much again for
    // The braking's lag behind the command).
    cap = std::min(
        cap, std::max(kTurnSpeed, stoppingSpeed(turn->distance - 2.0 * kOnCorner, p_.limits.accelMax, c.dt)));
  }
  if (v > cap) {
    w *= cap / v;
    v = cap;
  }
  mode = msg::RobotMode::Moving;
  // The gate keeps its gap along the base, which the roadmap keeps clear of shelves (see GateView).
  const std::vector<Vec2> gateRoute = stretch(basePath_, r->progress, kGateRoute);
  Blocker blocker;
  const double wanted = v;
  bool held = stack.heldUp(gateRoute, docking, v, w, blocker) && progress_.wantsToMove(wanted);
  if (!held && planning && !progress_.wantsToMove(std::abs(wanted)) && std::abs(w) < 0.1 && cap > 0.1) {
    // The planner stops in front of something (every rollout ends in the stop gap): held as well.
    Blocker any;
    localBlocked = stack.clearSpeed(gateRoute, docking, 0.5, any) < 0.5;
  }
  if (localBlocked && !held) {
    held = true;
    (void)stack.clearSpeed(gateRoute, docking, 0.5, blocker);  // name what is in the way
  }
  const Vec2 toCarrot = r->target.position() - here;
  const double bearing = angleDiff(std::atan2(toCarrot.y, toCarrot.x), pose.theta);
  // Turning on the spot below, the robot is still held by what is in its way: the hold's clock and
  // why it stands go by this. (Turned to its corner node, held by a person, turned back towards its
  // carrot and to the node again, a robot was never held at the end of a cycle: it stood 196 s
  // without saying it was blocked, a robot waiting 120 s behind it; dense check, seed 8.)
  const bool heldAhead = held;
  if (held && toCarrot.norm() > 0.1 && std::abs(bearing) > 0.25) {
    // Something ahead while the way bends away from it: turn towards the carrot on the spot, which
    // sweeps nothing. (Only for walls at first, as reactive: a robot 7 cm off its lane facing 24°
    // towards a robot parked beside the lane stood 1,200 s, full stack, seed 4.)
    v = 0.0;
    w = std::clamp(2.0 * bearing, -p_.wMax, p_.wMax);
    held = false;
  }
  // Waiting on a robot the traffic manager knows is a dependency, not a block; a person, something
  // not on the map or a robot the sensors cannot name is what the plan does not know about.
  const bool byKnownRobot = blocker.robot && stack.knowsRobot(blocker.id);
  if (held) {
    mode = msg::RobotMode::Waiting;
  }
  if (heldAhead) {
    standByObstacle_ = !blocker.robot && blocker.id.empty();
    standByPerson_ = !blocker.robot && blocker.id == "human";
    standWhy_ = blocker.robot        ? "held by robot " + blocker.id + (byKnownRobot ? "" : " (unknown)")
                : blocker.id.empty() ? std::string("held by an obstacle")
                                     : "held by " + blocker.id;
  }
  // A hold lasts until the robot has got on: a sampling planner turning this way and that in front
  // of a person is not held every cycle, and a blocked flag that flapped with it would have the
  // traffic manager re-plan on every report.
  if (heldSinceNs_ >= 0 && distance(here, heldAt_) > progress_.params().movedM) {
    heldSinceNs_ = -1;
  }
  if (heldAhead && !byKnownRobot && heldSinceNs_ < 0) {
    heldSinceNs_ = nowNs;
    heldAt_ = here;
  }
  blocked_ = (heldSinceNs_ >= 0 && nsToSec(nowNs - heldSinceNs_) > kBlockedAfterS) || givingWay();
  // Waiting on a dependency or a person runs no failure timer: the traffic manager re-plans.
  cmd.driver = planning ? Driver::kPlanner : Driver::kFollower;
  cmd.held = held;
  // What the robot-time ledger files the cycle under.
  if (held) {
    cmd.doing = byKnownRobot                              ? RobotActivity::WaitingOnRobot
                : !blocker.robot && blocker.id == "human" ? RobotActivity::HeldByPerson
                                                          : RobotActivity::HeldBySafety;
  } else if (aligning_ || cornering || settling || docking || undockFrom_ ||
             (std::abs(v) < 1e-9 && w != 0.0)) {
    cmd.doing = RobotActivity::TurningDocking;  // on the spot, at a corner, or on a station's leg
  } else {
    cmd.doing = RobotActivity::Driving;
  }
  cmd.waiting = held && (byKnownRobot || (!blocker.robot && blocker.id == "human"));
  return cmd;
}

void ReleaseFollower::noteStanding(const FollowCycle& c, const FollowCommand& cmd) {
  // Standing is not getting on (the progress watch's movedM): a planner turning this way and that
  // in front of a person stands as much as a robot told to. A robot on its way home counts too (one
  // stood 1,400 s 0.17 m from the end of its base, five robots behind it, and no log said so).
  const Vec2 here = c.pose.position();
  const auto& goal = c.goal;
  const bool onItsWay = c.busy || (goal && distance(here, goal->pose.position()) >= kAtGoal);
  if (!onItsWay || (standing_.sinceNs >= 0 && distance(here, standAt_) > progress_.params().movedM)) {
    standing_ = {};
  }
  if (!onItsWay) {
    return;
  }
  if (standing_.sinceNs < 0) {
    standing_.sinceNs = c.nowNs;
    standAt_ = here;
  }
  standing_.homing = !c.busy;
  if (!standWhy_.empty()) {
    standing_.why = standWhy_;  // the latest (a hold can change hands while the robot stands)
    standing_.byObstacle = standByObstacle_;
  } else if (standing_.why.empty()) {
    standing_.why = std::abs(cmd.v) > 1e-9 || std::abs(cmd.w) > 1e-9 ? kWhyOwnZero : kWhyStand;
  }
  standing_.next = releases_.next();
}

}  // namespace fleet::agent
