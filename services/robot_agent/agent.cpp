#include "agent.hpp"

#include <algorithm>
#include <cmath>

#include "axis_offset.hpp"
#include "disc_prediction.hpp"
#include "fleet/avoidance/rotation_shim.hpp"
#include "fleet/avoidance/safety_layer.hpp"
#include "fleet/core/angles.hpp"
#include "fleet/core/clock.hpp"
#include "fleet/geometry/grid_raycast.hpp"
#include "fleet/planning/astar.hpp"
#include "fleet/planning/ompl_planner.hpp"
#include "fleet/planning/return_path.hpp"
#include "fleet/planning/wavefront.hpp"
#include "map_faces.hpp"

#include <stdexcept>

namespace fleet::agent {
namespace {

LocalizerParams localizerParams(const AgentParams& p) {
  LocalizerParams lp;
  lp.start = p.start;
  lp.wheelBase = p.wheelBase;
  lp.sensorTimeoutS = p.sensorTimeoutS;
  lp.vMax = p.vMax;
  lp.wMax = p.wMax;
  lp.accelMax = p.limits.accelMax;
  lp.alphaMax = p.limits.alphaMax;
  lp.landmarks = p.landmarks;
  lp.walls = p.walls;
  lp.lineUpdates = p.lineUpdates;
  return lp;
}

SensorReading readingOf(const msg::SensorFrame& f) {
  SensorReading r;
  r.stampNs = f.stamp_ns;
  r.dsLeft = f.ds_left;
  r.dsRight = f.ds_right;
  r.wheelTotalsValid = f.wheel_totals_valid;
  r.wheelLeftTotal = f.wheel_left_total;
  r.wheelRightTotal = f.wheel_right_total;
  r.compassValid = f.compass_valid;
  r.compass = f.compass;
  r.bearings.reserve(f.landmarks.size());
  for (const auto& lb : f.landmarks) {
    r.bearings.emplace_back(lb.id, lb.bearing);
  }
  r.angleMin = f.angle_min;
  r.angleIncrement = f.angle_increment;
  r.rangeMax = f.range_max;
  r.ranges = f.ranges;
  r.sightings.reserve(f.detections.size());
  for (const auto& d : f.detections) {
    r.sightings.push_back(
        {d.kind == msg::SourceKind::Human ? SeenKind::kHuman : SeenKind::kRobot, d.x, d.y, d.r});
  }
  return r;
}

constexpr double kLookahead = 0.5;
/// In reserved traffic DWA's rollout at cruise ends this fraction of the way to its carrot (see
/// the constructor).
constexpr double kRolloutToCarrot = 0.8;
constexpr double kQueueDistance = 2.0;     // m from a station where a robot waits while it is taken
constexpr double kTrailStep = 0.25;        // m between trail points
constexpr double kUndockDistance = 1.0;    // m the follower drives off a station before the planner
constexpr double kAxisDistance = 1.0;      // m in front of a station: where its straight approach starts
constexpr std::size_t kTrailPoints = 120;  // 30 m of trail

OtherRobot::Mode modeOf(msg::RobotMode m) {
  switch (m) {
    case msg::RobotMode::Idle:
      return OtherRobot::Mode::kIdle;
    case msg::RobotMode::Moving:
      return OtherRobot::Mode::kMoving;
    case msg::RobotMode::Waiting:
      return OtherRobot::Mode::kWaiting;
    case msg::RobotMode::Loading:
      return OtherRobot::Mode::kLoading;
    case msg::RobotMode::Charging:
      return OtherRobot::Mode::kCharging;
    case msg::RobotMode::Fault:
      return OtherRobot::Mode::kFault;
    case msg::RobotMode::Blocked:
      break;
  }
  return OtherRobot::Mode::kBlocked;  // (and a value off the enum: none of the modes the rules look at)
}

control::PathFollowerParams followerParams() {
  control::PathFollowerParams fp;
  fp.lookahead = kLookahead;
  fp.goalToleranceXy = 0.15;
  fp.goalToleranceTheta = 0.25;
  return fp;
}

// The runner's actions are the wire's, in the same order.
static_assert(static_cast<int>(GoalAction::Park) == static_cast<int>(msg::GoalAction::Park) &&
              static_cast<int>(GoalAction::Charge) == static_cast<int>(msg::GoalAction::Charge) &&
              static_cast<int>(GoalAction::Unload) == static_cast<int>(msg::GoalAction::Unload) &&
              static_cast<int>(GoalAction::Load) == static_cast<int>(msg::GoalAction::Load));

TaskGoal goalOf(const msg::Goal& g) {
  return {g.pose, g.station, static_cast<GoalAction>(g.action), g.duration_s};
}

Order orderOf(const msg::TaskAssignment& a) {
  Order o{a.task_id, a.revision, {}, a.paused, a.stamp_ns, a.priority};
  o.goals.reserve(a.goals.size());
  for (const auto& g : a.goals) {
    o.goals.push_back(goalOf(g));
  }
  return o;
}

msg::TaskState wireState(TaskStage st) {
  switch (st) {
    case TaskStage::Queued:
      return msg::TaskState::Queued;
    case TaskStage::Assigned:
      return msg::TaskState::Assigned;
    case TaskStage::EnRoute:
      return msg::TaskState::EnRoute;
    case TaskStage::Loading:
      return msg::TaskState::Loading;
    case TaskStage::Delivering:
      return msg::TaskState::Delivering;
    case TaskStage::Unloading:
      return msg::TaskState::Unloading;
    case TaskStage::Done:
      return msg::TaskState::Done;
    case TaskStage::Failed:
      return msg::TaskState::Failed;
  }
  return msg::TaskState::Failed;
}

}  // namespace

avoidance::DwaParams agentDwaDefaults() {
  avoidance::DwaParams p;
  p.lookahead = 0.8;
  return p;
}

std::shared_ptr<const planning::OccupancyGrid> inflate(const planning::OccupancyGrid& raw, double radius) {
  return std::make_shared<const planning::OccupancyGrid>(raw.inflated(radius));
}

Agent::Agent(AgentParams params, std::shared_ptr<const planning::OccupancyGrid> grid,
             std::shared_ptr<const planning::OccupancyGrid> raw)
    : p_(std::move(params)),
      grid_(std::move(grid)),
      raw_(std::move(raw)),
      localizer_(localizerParams(p_)),
      lastPlausiblePose_(p_.start),
      follower_(followerParams()),
      gate_(GateParams{p_.radius, p_.stopGap, p_.headway, p_.traffic == "reserved" ? p_.robotStopGap : -1.0,
                       p_.limits, p_.speedLimit, p_.traffic != "reserved"}),
      standsAt_(p_.start),
      progress_(p_.progress),
      arbiter_(StandoffParams{p_.id, p_.radius, p_.blockedBackoffS, p_.blockedFailS}),
      route_(RouteOptions{p_.globalPlanner, p_.lanes, p_.riskWeightGlobal, p_.radius, p_.zoneLayers}, grid_,
             raw_) {
  if (p_.traffic != "reactive" && p_.traffic != "reserved") {
    throw std::invalid_argument("traffic: '" + p_.traffic + "' is not reactive or reserved");
  }
  reserved_ = p_.traffic == "reserved";
  if (p_.localPlanner != "follow") {
    using PlannerPtr = Expected<std::unique_ptr<avoidance::LocalPlanner>>;
    const bool stepping = p_.localPlanner == "risk_stepping" || p_.localPlanner == "risk_stepping_weighted";
    auto steppingParams = p_.riskStepping;
    if (p_.localPlanner == "risk_stepping_weighted") {
      steppingParams.rule = avoidance::SteppingRule::kWeighted;
    }
    auto dwa = p_.dwa;
    if (reserved_) {
      // DWA scores progress towards a carrot `lookahead` along the path over a `simTime` rollout,
      // which peaks where the rollout ends on the carrot: 0.8 m over 1.7 s is 0.47 m/s, and a lone
      // robot drove 72 % of its time at 0.4-0.6 m/s. A longer carrot cut shelf corners off the
      // base (a robot stood at one for good), so the rollout is shortened instead: at cruise it
      // ends a fifth short of the carrot. (Ending exactly on it, the heading term's bearing from
      // the rollout's end to the carrot swung sideways for a centimetre off the base, and a lone
      // robot drove 0.6-0.75 m/s for 40 % of its time: 1.39-1.42x its kinematic bound, 1.23-1.26x
      // with this and faster docking, docs/benchmarks.md. Reactive traffic keeps both; the
      // clearance term looks 2 m ahead either way.)
      dwa.simTime = std::min(dwa.simTime, kRolloutToCarrot * dwa.lookahead / p_.vMax);
    }
    auto inner = p_.localPlanner == "dwa" ? PlannerPtr(std::make_unique<avoidance::DynamicWindowPlanner>(dwa))
                 : stepping ? PlannerPtr(std::make_unique<avoidance::RiskSteppingPlanner>(steppingParams))
                            : avoidance::makePlanner(p_.localPlanner);
    if (!inner) {
      throw std::invalid_argument("local planner: " + inner.error().message);
    }
    // DWA turns in place towards the path first (Nav2's rotation shim): its acceleration window
    // alone cannot make the bend from a band into an aisle.
    if (p_.localPlanner == "dwa") {
      *inner = std::make_unique<avoidance::RotationShim>(std::move(*inner));
    }
    auto safety = p_.safety;
    // A released base keeps 0.1 m from shelves (inside the slow-down zone's 0.3 m): slowing for
    // them made every aisle a 0.4 m/s zone. People and robots still slow the robot.
    safety.slowForStatic = safety.slowForStatic && !reserved_;
    planner_ = std::make_unique<avoidance::SafePlanner>(std::move(*inner), safety);
  }
}

control::Twist Agent::planLocal(bool& blocked) {
  const Pose2 pose = localizer_.pose();
  // Drop the path points already passed: keep from the one nearest to the robot.
  std::size_t nearest = 0;
  for (std::size_t i = 0; i < path_.size() && i < 40; ++i) {
    if (distance(path_[i], pose.position()) < distance(path_[nearest], pose.position())) {
      nearest = i;
    }
  }
  path_.erase(path_.begin(), path_.begin() + static_cast<std::ptrdiff_t>(nearest));
  const Perception& seen = localizer_.perception();
  std::vector<Vec2> scan = seen.scanPoints(3.0);
  // The map's walls and shelves near the robot as well (a local costmap's static layer): 72 rays
  // are 26 cm apart at 3 m, and a shelf corner between two of them was not there for the planner.
  const std::vector<Vec2> walls = mapFaces(*raw_, pose.position(), 2.0);
  scan.insert(scan.end(), walls.begin(), walls.end());
  std::vector<avoidance::MovingDisc> discs;
  // Robots as they report themselves (with their velocity) and people as tracked from frame to
  // frame, as well as whatever is detected: a robot known only from its RobotState (out of the
  // sensor's view, or a driver without detections) must still be kept clear of.
  for (const auto& o : others_) {
    if (distance(o.pos, pose.position()) < 3.0) {
      discs.push_back({o.pos, o.velocity, p_.radius});
    }
  }
  for (const auto& h : seen.people) {
    discs.push_back({h.pos, h.velocity, h.radius});
  }
  for (const auto& d : seen.detections) {
    discs.push_back({d.map, {}, d.radius});
  }
  avoidance::LocalView view;
  view.robot = {pose, {v_, w_}, p_.radius};
  view.path = path_;
  view.scan = scan;
  view.discs = discs;
  view.limits = p_.limits;
  view.dt = 0.1;
  view.goalTolerance = 0.15;
  if (risk_) {
    view.risk = [r = risk_](Vec2 q) { return r->at(q); };
  }
  const auto cmd = planner_->plan(view);
  blocked = cmd.status == avoidance::PlanStatus::kBlocked ||
            (cmd.overruled && std::abs(cmd.twist.v) < 0.05 && std::abs(cmd.twist.omega) < 0.05);
  return cmd.twist;
}

GateView Agent::gateView() const {
  return {localizer_.perception(),
          others_,
          *raw_,
          {v_, w_},
          docking_,
          gateRoute_.empty() ? nullptr : &gateRoute_};
}

double Agent::clearSpeed(double v, Blocker& blocker) {
  const auto c = gate_.clearSpeed(gateView(), v, blocker);
  blockPoint_ = c.blockPoint;
  return c.speed;
}

bool Agent::heldUp(double& v, double& w, Blocker& blocker) {
  const auto h = gate_.heldUp(gateView(), v, w, blocker);
  blockPoint_ = h.blockPoint;
  return h.held;
}

bool Agent::rearClear() const {
  return gate_.rearClear(gateView());
}

void Agent::onFrame(const msg::SensorFrame& f) {
  localizer_.onReading(readingOf(f));
  if (std::isfinite(f.battery)) {
    battery_ = static_cast<double>(f.battery);
  }
}

void Agent::onOtherRobot(const msg::RobotState& s) {
  if (s.robot_id == p_.id || !s.pose.isFinite()) {
    return;
  }
  auto it = std::find_if(others_.begin(), others_.end(), [&](const Other& o) { return o.id == s.robot_id; });
  if (it == others_.end()) {
    others_.push_back({s.robot_id, {}, Other::Mode::kIdle, false, {}, 0.0, -1, 0});
    it = std::prev(others_.end());
  }
  Other& o = *it;
  if (s.mode != msg::RobotMode::Waiting) {
    o.waitingSinceNs = -1;
  } else if (o.waitingSinceNs < 0 || o.mode != Other::Mode::kWaiting) {
    o.waitingSinceNs = s.stamp_ns;
  }
  o.pos = s.pose.position();
  o.theta = s.pose.theta;
  o.mode = modeOf(s.mode);
  o.hasTask = !s.task_id.empty();
  o.velocity = Vec2{std::cos(s.pose.theta), std::sin(s.pose.theta)} * s.v;
  o.stampNs = s.stamp_ns;
}

void Agent::onAssignment(const msg::TaskAssignment& a) {
  if (a.robot_id != p_.id) {
    return;
  }
  switch (tasks_.accept(orderOf(a))) {
    case TaskRunner::OrderChange::kSame:
      return;
    case TaskRunner::OrderChange::kCancel:
    case TaskRunner::OrderChange::kPause:
    case TaskRunner::OrderChange::kRefused:
      idleSinceNs_ = -1;
      return;
    case TaskRunner::OrderChange::kNewTask:
      idleSinceNs_ = -1;
      holdSinceNs_ = -1;
      progress_.newOrder();
      return;
  }
}

void Agent::refuseAssignment(const msg::TaskAssignment& a, const std::string& why) {
  if (a.robot_id == p_.id) {
    tasks_.refuse(orderOf(a), why);
  }
}

planning::OccupancyGrid Agent::gridAroundStandingRobots(Vec2 goal) const {
  planning::OccupancyGrid g = *grid_;
  const double res = g.resolution();
  // Centre-to-centre distance at contact plus room for the safety layer's slow-down zone.
  const double keep = 2.0 * p_.radius + 0.2;
  const Vec2 self = localizer_.pose().position();
  for (const auto& o : others_) {
    // Never wall in the goal: a robot parked on my goal is a wait, not a detour. (The robot's own
    // surroundings are opened again below.) Its neighbours (parking places 1 m apart) keep only
    // their bodies' disc, so the way in comes from in front of the place and not over them.
    const double toGoal = distance(o.pos, goal);
    if (!standing(o) || toGoal < 2.0 * p_.radius + 0.1) {
      continue;
    }
    const double around = toGoal < keep + res ? 2.0 * p_.radius + 0.05 : keep;
    const auto c = g.cellAt(o.pos);
    if (!c) {
      continue;
    }
    const int reach = static_cast<int>(std::ceil(around / res));
    for (int dy = -reach; dy <= reach; ++dy) {
      for (int dx = -reach; dx <= reach; ++dx) {
        const planning::Cell q{c->x + dx, c->y + dy};
        if (g.inside(q) && distance(g.cellCenter(q), o.pos) < around) {
          g.setBlocked(q);
        }
      }
    }
  }
  // A robot parked closer to a wall than the planning margin starts in a blocked cell; open the
  // cells around it that are free on the map and not next to a standing robot, so the plan leads
  // out of the parking place instead of falling back to the raw map (which ignores the neighbours).
  if (const auto c = g.cellAt(self); c && g.blocked(*c)) {
    const double open = p_.radius + 0.35;
    const int reach = static_cast<int>(std::ceil(open / res));
    for (int dy = -reach; dy <= reach; ++dy) {
      for (int dx = -reach; dx <= reach; ++dx) {
        const planning::Cell q{c->x + dx, c->y + dy};
        if (!g.inside(q) || distance(g.cellCenter(q), self) > open) {
          continue;
        }
        bool nearStanding = false;
        for (const auto& o : others_) {
          nearStanding = nearStanding || (standing(o) && distance(o.pos, g.cellCenter(q)) < keep);
        }
        if (bodyFits(g.cellCenter(q)) && !nearStanding) {
          g.setBlocked(q, false);
        }
      }
    }
    // The robot's own cell, whatever its centre fits: the robot stands there. A parking place at
    // y = 0.9 lies in a cell whose centre is 0.25 m from the wall, so its body never "fits" there,
    // the plan from it failed, and every trip from home fell back to the raw map, whose paths run
    // 0.25 m from shelf faces (the local planner then crawled past each shelf corner).
    g.setBlocked(*c, false);
  }
  openGoal(g, *raw_, goal, p_.radius);
  return g;
}

bool Agent::bodyFits(Vec2 p) const {
  return agent::bodyFits(*raw_, p, p_.radius);
}

std::optional<Vec2> Agent::axisPoint(const Pose2& station, const planning::OccupancyGrid& g) const {
  const Vec2 at = station.position();
  const Vec2 u = station.heading();
  const Vec2 a = at + u * kAxisDistance;
  if (const auto c = g.cellAt(a); !c || g.blocked(*c)) {
    return std::nullopt;  // a pickup 0.75 m from its shelf: approached along the row instead
  }
  for (double s = 0.1; s < kAxisDistance; s += 0.1) {
    if (!bodyFits(at + u * s)) {
      return std::nullopt;
    }
  }
  for (const auto& o : others_) {
    // Standing on the leg (not on the station itself: that is a queue, see stationOccupant).
    const double along = std::clamp((o.pos - at).dot(u), 0.0, kAxisDistance);
    if (standing(o) && distance(o.pos, at) > 2.0 * p_.radius + 0.1 &&
        distance(o.pos, at + u * along) < 2.0 * p_.radius) {
      return std::nullopt;
    }
  }
  return a;
}

bool Agent::onAxis(Vec2 p, const Pose2& station) const {
  const auto [along, lateral] = axisOffset(station, p);
  return along > -0.1 && along < kAxisDistance + 0.3 && lateral < 0.2;
}

void Agent::startGoal(std::int64_t nowNs, std::optional<Vec2> avoid) {
  if (reserved_) {
    beginLeg(nowNs);  // the route comes with the releases
    return;
  }
  const auto& g = tasks_.goal();
  // Leaving a station or parking place (not re-planning on the way): see undockFrom_.
  const bool fromStandstill = tasks_.phase() == Phase::Idle || tasks_.phase() == Phase::Dwelling;
  const planning::OccupancyGrid around = gridAroundStandingRobots(g.pose.position());
  // Stations are left and entered straight along their axis, through a point kAxisDistance in
  // front of them (a dock's pre-dock pose, VDA 5050's approach pose). A path straight from a
  // parking place to an aisle, or from an aisle onto a parking place, runs diagonally past the
  // robots parked next to it: two neighbours leaving together each blocked the other's way out
  // (both tasks failed after 60 s, three times over), and a robot coming home beside a parked
  // neighbour stood there for good.
  const Pose2 here = localizer_.pose();
  Pose2 from = here;
  Pose2 to = g.pose;
  std::vector<Pose2> head;
  std::vector<Pose2> tail;
  // (Leaving for somewhere a couple of metres off, a station just behind, say, or for a goal
  // behind the station's front, goes there directly: the axis would be a U-turn. Coming in, the
  // axis counts wherever the robot replans from.)
  const bool shortMove = distance(here.position(), g.pose.position()) < 2.0 * kAxisDistance;
  const bool ahead = axisOffset(standsAt_, g.pose.position()).along > 0.0;
  if (!shortMove && ahead && distance(here.position(), standsAt_.position()) < 0.3) {
    if (const auto e = axisPoint(standsAt_, around)) {
      from = {e->x, e->y, standsAt_.theta};
      head = {here};
    }
  }
  if (!onAxis(here.position(), g.pose)) {
    if (const auto a = axisPoint(g.pose, around)) {
      const double in = wrapAngle(g.pose.theta + kPi);
      to = {a->x, a->y, in};
      tail = {Pose2{g.pose.x, g.pose.y, in}};
    }
  }
  auto plan = [&](const Pose2& start, const Pose2& end) -> Expected<planning::Path> {
    if (avoid) {
      const Vec2 self = here.position();
      planning::OccupancyGrid detour = around;
      const double res = detour.resolution();
      const int reach = static_cast<int>(std::ceil(0.9 / res));
      if (const auto c = detour.cellAt(*avoid)) {
        for (int dy = -reach; dy <= reach; ++dy) {
          for (int dx = -reach; dx <= reach; ++dx) {
            const planning::Cell q{c->x + dx, c->y + dy};
            // Close to the obstacle the robot stands inside that disc itself: keep free the cells
            // next to it on the side away from the obstacle, so the detour can start by leaving.
            const Vec2 off = detour.inside(q) ? detour.cellCenter(q) - self : Vec2{};
            const bool leaving = off.norm() < p_.radius + 0.15 && off.dot(*avoid - self) <= 0.0;
            if (detour.inside(q) && distance(detour.cellCenter(q), *avoid) <= 0.9 && !leaving) {
              detour.setBlocked(q);
            }
          }
        }
      }
      if (const auto c = detour.cellAt(start.position())) {
        // The robot's own cell (the disc covers it when it stands close): a plan must start.
        detour.setBlocked(*c, false);
      }
      return route_.detour(detour, start, end);  // no way around: the caller keeps its path
    }
    return route_.route(around, start, end);
  };
  Expected<planning::Path> path = plan(from, to);
  approach_.reset();
  if (path) {
    path->poses.insert(path->poses.begin(), head.begin(), head.end());
    if (!tail.empty()) {
      approach_ = tail.back();  // driven once the robot is at the axis point (see drive)
    }
  } else if (!head.empty() || !tail.empty()) {
    path = plan(here, g.pose);  // the axis leads nowhere from here: plainly
  }
  if (!path && avoid) {
    return;  // no way around: keep the current path and wait
  }
  if (!path || !follower_.setPath(path->poses)) {
    finishTask(TaskStage::Failed,
               "no path to " + (g.station.empty() ? std::string("goal") : g.station) + ": " +
                   (path ? std::string("follower refused the path") : path.error().message),
               nowNs);
    return;
  }
  path_.clear();
  for (const auto& q : path->poses) {
    path_.push_back(q.position());
  }
  if (planner_) {
    planner_->reset();
  }
  if (fromStandstill) {
    undockFrom_ = localizer_.pose().position();
  }
  tasks_.leg(nowNs);
  blockedSinceNs_ = -1;
  straightDock_ = false;
  makingRoom_ = false;
}

void Agent::finishTask(TaskStage final, const std::string& reason, std::int64_t nowNs) {
  if (tasks_.homing() && final != TaskStage::Done) {
    homeRetryNs_ = nowNs + secToNs(30.0);  // the trip home failed: retry later
  }
  tasks_.finish(final, reason, nowNs);
  idleSinceNs_ = nowNs;
  holdSinceNs_ = -1;
  progress_.taskEnded();
}

void Agent::followerTwist(const control::PathFollowerOutput& r, double& v, double& w) const {
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
  const Vec2 toCarrot = r.target.position() - localizer_.pose().position();
  const double bearing = angleDiff(std::atan2(toCarrot.y, toCarrot.x), localizer_.pose().theta);
  if (!r.finalApproach && toCarrot.norm() > 0.05 && std::abs(bearing) > 0.7) {
    v = 0.0;
    w = std::clamp(2.0 * bearing, -p_.wMax, p_.wMax);
  }
}

double Agent::freeWidth(Vec2 p, Vec2 dir) const {
  const double n = dir.norm();
  if (n < 1e-9) {
    return 0.0;
  }
  const double across = std::atan2(dir.x, -dir.y);  // the left normal of dir
  const auto view = raw_->view();
  return geometry::raycastGrid(view, p, across, 3.0).range +
         geometry::raycastGrid(view, p, across + kPi, 3.0).range;
}

bool Agent::narrow(Vec2 p, Vec2 dir) const {
  // Two robots side by side with 0.1 m between them and to each wall.
  return freeWidth(p, dir) < 4.0 * p_.radius + 0.3;
}

bool Agent::startReturn(std::int64_t nowNs) {
  const Vec2 here = localizer_.pose().position();
  const Vec2 heading{std::cos(localizer_.pose().theta), std::sin(localizer_.pose().theta)};
  if (trail_.size() < 2 || !narrow(here, heading)) {
    return false;
  }
  // Walk the trail back to the first point wide enough for the other robot to pass, at least a
  // body length away (the trail's newest point may be where the robot stands).
  std::vector<Vec2> skeleton{here};
  double travelled = 0.0;
  bool found = false;
  for (std::size_t i = trail_.size(); i-- > 0;) {
    const Vec2 q = trail_[i];
    if (distance(q, skeleton.back()) < 0.05) {
      continue;
    }
    travelled += distance(q, skeleton.back());
    const Vec2 dir = q - skeleton.back();
    skeleton.push_back(q);
    if (travelled > 2.0 * p_.radius + 0.5 && !narrow(q, dir)) {
      found = true;
      break;
    }
  }
  if (!found) {
    return false;
  }
  // The trail was driven, so it is free of what the map does not show; seed 001's return path
  // shortens it around the inside of each turn (falling back to the trail itself).
  std::vector<Vec2> points = skeleton;
  if (auto rp = planning::planReturnPath(*grid_, skeleton)) {
    points = rp->points;
  }
  const Vec2 last = points.back() - points[points.size() - 2];
  if (!follower_.setPath(points, std::atan2(last.y, last.x))) {
    return false;
  }
  path_ = points;
  tasks_.yieldBy(Phase::Returning, nowNs);
  blockedSinceNs_ = -1;
  backoffFrom_ = blockPoint_;
  trail_.clear();  // the way back is driven now; what it leaves behind starts a new trail
  ++conduct_.returns;
  return true;
}

void Agent::enterDwell(std::int64_t nowNs) {
  standsAt_ = tasks_.goal().pose;
  tasks_.arrive(nowNs);
}

void Agent::onStandoff(std::int64_t nowNs, bool byRobot, const std::string& blocker, double& v, double& w) {
  if (blockedSinceNs_ < 0) {
    blockedSinceNs_ = nowNs;
  }
  Standoff s;
  s.nowNs = nowNs;
  s.sinceNs = blockedSinceNs_;
  s.byRobot = byRobot;
  s.blocker = blocker;
  s.blockPointKnown = blockPoint_.has_value();
  s.homing = tasks_.homing();
  s.position = localizer_.pose().position();
  const StandoffDecision d = arbiter_.decide(s, others_);
  if (d.newStandoff) {
    ++conduct_.standoffs;
  }
  conduct_.mutualBlocks += static_cast<std::uint64_t>(d.waitCycles);
  StandoffMove move = d.move;
  if (move == StandoffMove::kPlanAroundStanding) {
    ++conduct_.detours;
    // The clock keeps running: when the new plan leads into the same hold, the rules below
    // (back off, detour around the point, fail) must still get their turn. Restarting it here
    // kept a robot re-planning the same path every 3 s for minutes.
    const std::int64_t since = blockedSinceNs_;
    startGoal(nowNs);
    blockedSinceNs_ = since;
    return;
  }
  if (move == StandoffMove::kYield) {
    if (startReturn(nowNs)) {
      v = 0.0;
      w = 0.0;
      return;
    }
    if (rearClear()) {
      tasks_.yieldBy(Phase::BackingOff, nowNs);
      backoffFrom_ = blockPoint_;
      ++conduct_.backoffs;
      return;
    }
    move = arbiter_.cannotYield(s);
  }
  if (move == StandoffMove::kDetour) {
    ++conduct_.detours;
    startGoal(nowNs, blockPoint_);
  } else if (move == StandoffMove::kFail) {
    finishTask(TaskStage::Failed,
               "blocked by " + (blocker.empty() ? std::string("an obstacle") : blocker) + " for " +
                   std::to_string(static_cast<int>(p_.blockedFailS)) + " s",
               nowNs);
    v = 0;
    w = 0;
  }
}

bool Agent::sensorStreamLost(std::int64_t nowNs) {
  const StreamCheck c = localizer_.checkStream(nowNs);
  if (c.change == StreamCheck::Change::kNone) {
    return c.lost;
  }
  std::string reason;
  if (c.change == StreamCheck::Change::kLost) {
    reason = "sensor stream lost: no SensorFrame for " + std::to_string(c.silentS) + " s";
  } else {
    // The outage is not time spent blocked or without progress.
    if (blockedSinceNs_ >= 0) {
      blockedSinceNs_ += c.outageNs;
    }
    progress_.afterOutage(c.outageNs);
    if (planner_) {
      planner_->reset();
    }
  }
  tasks_.notice(reason, nowNs);
  return c.lost;
}

AgentOutput Agent::step(std::int64_t nowNs, double dt) {
  if (!localizer_.plausible()) {
    // The estimate left the world (non-finite, or farther than any map): nothing it would plan or
    // report means anything, and it does not come back by itself. Stop, give the task back and say
    // so, rather than report an idle robot the manager would give the next task.
    AgentOutput out;
    v_ = 0.0;
    w_ = 0.0;
    heldSinceNs_ = -1;
    blocked_ = false;
    if (tasks_.busy()) {
      finishTask(TaskStage::Failed, "localization estimate implausible", nowNs);
    }
    report(out, nowNs, 0.0, 0.0, msg::RobotMode::Fault);
    return out;
  }
  if (!sensorStreamLost(nowNs)) {
    return drive(nowNs, dt);
  }
  // Blind: hold still and say why; the task is kept and resumes when frames come back.
  AgentOutput out;
  v_ = 0.0;
  w_ = 0.0;
  heldSinceNs_ = -1;  // (reserved traffic: holding, not blocked)
  blocked_ = false;
  report(out, nowNs, 0.0, 0.0, msg::RobotMode::Fault);
  return out;
}

AgentOutput Agent::drive(std::int64_t nowNs, double dt) {
  AgentOutput out;
  drove_ = {};
  if (tasks_.paused()) {
    // Held by the operator: stand still with the task; the hold is no time blocked or dwelling.
    if (pausedSinceNs_ < 0) {
      pausedSinceNs_ = nowNs;
    }
    v_ = 0.0;
    w_ = 0.0;
    heldSinceNs_ = -1;  // (reserved traffic: holding, not blocked)
    blocked_ = false;
    report(out, nowNs, 0.0, 0.0, msg::RobotMode::Waiting);
    return out;
  }
  if (pausedSinceNs_ >= 0) {
    const std::int64_t held = nowNs - pausedSinceNs_;
    pausedSinceNs_ = -1;
    for (std::int64_t* t : {&blockedSinceNs_, &holdSinceNs_}) {
      if (*t >= 0) {
        *t += held;
      }
    }
    tasks_.shiftClock(held);
    progress_.afterOutage(held);
    if (planner_) {
      planner_->reset();
    }
  }
  double v = 0.0;
  double w = 0.0;
  msg::RobotMode mode = msg::RobotMode::Idle;
  if (reserved_) {
    followRelease(nowNs, dt, v, w, mode);
    watchProgress(nowNs);
    v_ = v;
    w_ = w;
    report(out, nowNs, v, w, mode);
    return out;
  }
  if (tasks_.hasOrder() && tasks_.phase() == Phase::Idle) {
    startGoal(nowNs);
  }
  maybeReturnHome(nowNs);
  if (tasks_.phase() == Phase::Driving) {
    auto r = follower_.step(localizer_.pose());
    if (r && approach_ && r->finalApproach && !path_.empty() &&
        distance(localizer_.pose().position(), path_.back()) < 0.25) {
      // At the station's axis point: the last leg, straight in. Followed as one path, the local
      // planner cut the corner onto the axis and came in diagonally past the neighbours again.
      path_ = {localizer_.pose().position(), approach_->position()};
      (void)follower_.setPath(path_, approach_->theta);
      approach_.reset();
      if (planner_) {
        planner_->reset();
      }
      r = follower_.step(localizer_.pose());
    }
    if (!r) {
      finishTask(TaskStage::Failed, "path follower: " + r.error().message, nowNs);
    } else if (!approach_ && (r->goalReached ||
                              (r->finalApproach && distance(localizer_.pose(), tasks_.goal().pose) < 0.15))) {
      enterDwell(nowNs);
    } else if (const Other* occupant = stationOccupant(); occupant != nullptr) {
      // Queue for the station a little way off instead of pushing into the robot on it.
      mode = msg::RobotMode::Waiting;
      if (holdSinceNs_ < 0) {
        holdSinceNs_ = nowNs;
      } else if (nsToSec(nowNs - holdSinceNs_) > p_.blockedFailS) {
        finishTask(TaskStage::Failed,
                   tasks_.goal().station + " occupied by " + occupant->id + " for " +
                       std::to_string(static_cast<int>(p_.blockedFailS)) + " s",
                   nowNs);
      }
      // The robot on the station wants out (it reports waiting or moving: held up, most likely by
      // this queue, which stands where its way out begins). Back away up to 1 m more, so it can
      // pass; a queue robot and the occupant waiting on each other failed both tasks after 60 s.
      const bool wantsOut = occupant->mode == Other::Mode::kWaiting || occupant->mode == Other::Mode::kMoving;
      if (wantsOut && distance(localizer_.pose(), tasks_.goal().pose) < kQueueDistance + 1.0 && rearClear()) {
        v = -0.2;
        makingRoom_ = true;
      }
      progress_.queueing(nowNs);
    } else {
      holdSinceNs_ = -1;
      makingRoom_ = false;
      docking_ = r->finalApproach && !approach_;
      // The configured planner drives the path; the follower's pose law docks (a sampling
      // planner stops near the goal, not on it with the goal's heading). Either command then goes
      // through the same stop rule and standoff handling below, so yielding, backing off and
      // detours work the same whichever planner drives.
      bool localBlocked = false;
      if (undockFrom_ && distance(localizer_.pose().position(), *undockFrom_) > kUndockDistance) {
        undockFrom_.reset();
      }
      const bool planning = planner_ && !docking_ && !undockFrom_ && !progress_.followerDrives(nowNs);
      if (planning) {
        const auto tw = planLocal(localBlocked);
        v = tw.v;
        w = tw.omega;
      } else {
        followerTwist(*r, v, w);
      }
      if (docking_ && (straightDock_ || planner_)) {
        // Face the station, then drive straight onto it (see below). Always after a sampling
        // planner: it reaches the final approach off the path's last leg, from where the pose
        // law's curve onto the station's heading swept into the robots parked beside it.
        const Vec2 to = r->target.position() - localizer_.pose().position();
        const double b = angleDiff(std::atan2(to.y, to.x), localizer_.pose().theta);
        w = std::clamp(2.0 * b, -p_.wMax, p_.wMax);
        v = std::abs(b) > 0.25 ? 0.0 : std::min(0.3, to.norm());
      }
      mode = msg::RobotMode::Moving;
      Blocker blocker;
      const double wanted = v;
      // Held: the stop rule cut a command that wanted to move (one threshold whoever drives; see
      // ProgressParams::wantSpeed).
      bool held = heldUp(v, w, blocker) && progress_.wantsToMove(wanted);
      if (!held && planning && !progress_.wantsToMove(std::abs(wanted)) && std::abs(w) < 0.1) {
        // The planner stops the robot in front of something (every rollout ends in the stop
        // gap): as blocked as when the stop rule holds it. Counted only while the stop rule held
        // it, a homing robot facing one on an order in the wide top band alternated a second
        // "held" with seconds of the planner's standstill, its blocked clock restarted each time,
        // it never yielded, and the other's task failed after 60 s.
        Blocker any;
        localBlocked = clearSpeed(0.5, any) < 0.5;
      }
      if (localBlocked && !held) {
        // The planner found no admissible move: name what is in the way (probing a speed it
        // would like) so the standoff rules know whom to yield to.
        held = true;
        (void)clearSpeed(0.5, blocker);
      }
      const Vec2 toCarrot = r->target.position() - localizer_.pose().position();
      const double bearing = angleDiff(std::atan2(toCarrot.y, toCarrot.x), localizer_.pose().theta);
      if (held && !blocker.robot && blocker.id.empty() && toCarrot.norm() > 0.1 && std::abs(bearing) > 0.25) {
        // A wall or shelf ahead while the path bends away (a diagonal A* step into a band): turn
        // toward the carrot on the spot, which no static obstacle can stop, instead of waiting.
        // Docking too: the pose law's curve onto a station beside a wall runs through the wall, and
        // the law keeps asking for it (it left robots facing the wall 0.2 m off their parking
        // place); from then on the robot faces the station and drives straight onto it.
        v = 0.0;
        w = std::clamp(2.0 * bearing, -p_.wMax, p_.wMax);
        blockedSinceNs_ = -1;
        straightDock_ = r->finalApproach;
      } else if (held) {
        mode = msg::RobotMode::Waiting;
        onStandoff(nowNs, blocker.robot, blocker.id, v, w);
      } else {
        blockedSinceNs_ = -1;
      }
      drove_ = {planning ? Driver::kPlanner : Driver::kFollower, held, false};
    }
  } else if (tasks_.phase() == Phase::Returning) {
    mode = msg::RobotMode::Waiting;  // yielding: nobody should wait on this robot's progress
    auto r = follower_.step(localizer_.pose());
    const bool arrived =
        !r || r->goalReached ||
        (r->finalApproach && path_.size() > 0 && distance(localizer_.pose().position(), path_.back()) < 0.25);
    Blocker blocker;
    if (!arrived) {
      docking_ = false;
      followerTwist(*r, v, w);
      const double wanted = v;
      const bool held = heldUp(v, w, blocker) && progress_.wantsToMove(wanted);
      if (held) {
        if (blockedSinceNs_ < 0) {
          blockedSinceNs_ = nowNs;
        }
      } else {
        blockedSinceNs_ = -1;
      }
      drove_ = {Driver::kFollower, held, false};
    }
    // At the wide place (or stuck on the way back for a while): replan around what blocked it.
    if (arrived || (blockedSinceNs_ >= 0 && nsToSec(nowNs - blockedSinceNs_) > p_.blockedBackoffS)) {
      v = 0.0;
      w = 0.0;
      endYield(nowNs);
    }
  } else if (tasks_.phase() == Phase::Dwelling) {
    mode = tasks_.goal().action == GoalAction::Charge ? msg::RobotMode::Charging : msg::RobotMode::Loading;
    if (tasks_.dwellOver(nowNs)) {
      const bool more = tasks_.nextGoal();
      progress_.newGoal();
      if (!more) {
        finishTask(TaskStage::Done, "", nowNs);
      } else {
        startGoal(nowNs);
      }
    }
  } else if (tasks_.phase() == Phase::BackingOff) {
    mode = msg::RobotMode::Waiting;
    v = rearClear() ? -0.2 : 0.0;
    if (nsToSec(nowNs - tasks_.phaseStartNs()) > 1.5) {
      endYield(nowNs);
    }
  }
  watchProgress(nowNs);
  if (tasks_.phase() == Phase::Driving) {
    const Vec2 here = localizer_.pose().position();
    if (trail_.empty() || distance(trail_.back(), here) > kTrailStep) {
      trail_.push_back(here);
      if (trail_.size() > kTrailPoints) {
        trail_.erase(trail_.begin());
      }
    }
  }
  v_ = v;
  w_ = w;
  (void)dt;
  report(out, nowNs, v, w, mode);
  return out;
}

void Agent::endYield(std::int64_t nowNs) {
  // Replan from where it stands around what blocked it (the same path would lead straight back
  // into the standoff); with no way around, the plain plan.
  tasks_.stop();
  if (backoffFrom_) {
    ++conduct_.detours;
    startGoal(nowNs, backoffFrom_);
  }
  if (tasks_.phase() != Phase::Driving && tasks_.hasOrder()) {
    startGoal(nowNs);
  }
  backoffFrom_.reset();
}

void Agent::watchProgress(std::int64_t nowNs) {
  ProgressSample sample;
  sample.nowNs = nowNs;
  sample.here = localizer_.pose().position();
  sample.travelling = tasks_.phase() == Phase::Driving || tasks_.phase() == Phase::Returning ||
                      tasks_.phase() == Phase::BackingOff;
  if (tasks_.hasGoal()) {
    sample.goal = tasks_.goal().pose.position();
  }
  if (reserved_) {
    // Progress is along the released nodes (a route on the roadmap may lead away from the goal for
    // a while). Waiting for a release is waiting on another robot, not being stuck: no clock runs.
    sample.travelling = tasks_.phase() == Phase::Driving && baseAhead_;
    sample.goal = releases_.next();
  }
  sample.hasOrder = tasks_.hasOrder();
  sample.driver = drove_.driver;
  sample.held = drove_.held;
  sample.waiting = drove_.waiting;
  switch (progress_.check(sample)) {
    case ProgressVerdict::kFailTask:
      finishTask(TaskStage::Failed,
                 "no progress towards " + tasks_.goal().station + " for " +
                     std::to_string(progress_.failAfterS()) + " s",
                 nowNs);
      break;
    case ProgressVerdict::kStalled:
      onStall(nowNs);
      break;
    case ProgressVerdict::kNone:
      break;
  }
}

void Agent::onStall(std::int64_t nowNs) {
  if (drove_.driver == Driver::kPlanner) {
    ++conduct_.plannerRecoveries;  // the progress watch hands the drive to the follower for a while
    return;
  }
  if (reserved_) {
    return;  // the follower keeps to the released base; re-planning it is the traffic manager's
  }
  ++conduct_.plannerRecoveries;
  if (tasks_.phase() == Phase::Returning) {
    endYield(nowNs);  // the way back is held up too (and not by the stop rule): plan from here
  } else if (tasks_.phase() == Phase::Driving) {
    startGoal(nowNs);  // the follower is stuck on this path: a new one from where the robot is
  }
}

const Agent::Other* Agent::stationOccupant() const {
  const auto& g = tasks_.goal();
  const Vec2 here = localizer_.pose().position();
  const double toGoal = distance(here, g.pose.position());
  const double reach = makingRoom_ ? kQueueDistance + 1.3 : kQueueDistance;  // (hysteresis)
  if (tasks_.homing() || toGoal > reach || toGoal < kQueueDistance - 0.5) {
    return nullptr;  // far off, or already past the queue place: go on
  }
  for (const auto& o : others_) {
    if (distance(o.pos, g.pose.position()) < 2.0 * p_.radius + 0.1) {
      return &o;
    }
  }
  return nullptr;
}

void Agent::maybeReturnHome(std::int64_t nowNs) {
  if (tasks_.hasOrder() || tasks_.phase() != Phase::Idle || p_.returnHomeS < 0.0) {
    return;
  }
  if (idleSinceNs_ < 0) {
    idleSinceNs_ = nowNs;
  }
  // Someone waiting close by may be queueing for the station this robot stands on: leave at once.
  const bool wanted = std::any_of(others_.begin(), others_.end(), [&](const Other& o) {
    return o.mode == Other::Mode::kWaiting &&
           distance(o.pos, localizer_.pose().position()) < kQueueDistance + 0.5;
  });
  if (nsToSec(nowNs - idleSinceNs_) < (wanted ? std::min(1.0, p_.returnHomeS) : p_.returnHomeS) ||
      nowNs < homeRetryNs_ || distance(localizer_.pose().position(), p_.start.position()) < 0.3) {
    return;
  }
  tasks_.goHome(TaskGoal{p_.start, "home", GoalAction::Park, 0.0});
  progress_.newGoal();
  startGoal(nowNs);
}

void Agent::report(AgentOutput& out, std::int64_t nowNs, double v, double w, msg::RobotMode mode) {
  // An implausible estimate is reported as the last plausible pose with a covariance that says it
  // is unknown: the fault stays visible to the manager and operators, whose edges refuse NaN.
  const bool plausible = localizer_.plausible();
  if (plausible) {
    lastPlausiblePose_ = localizer_.pose();
  }
  const Pose2 pose = lastPlausiblePose_;
  const Eigen::Matrix3d P =
      plausible ? localizer_.covariance() : Eigen::Matrix3d(Eigen::Vector3d(1e12, 1e12, 1e3).asDiagonal());
  out.command = {p_.id, v, w, nowNs, 0};
  out.state.robot_id = p_.id;
  out.state.stamp_ns = nowNs;
  out.state.pose = pose;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      out.state.covariance[static_cast<std::size_t>(3 * i + j)] = P(i, j);
    }
  }
  out.state.v = v;
  out.state.w = w;
  out.state.mode = mode;
  out.state.battery = static_cast<float>(battery_);
  out.state.task_id = tasks_.task();
  out.state.radius = static_cast<float>(p_.radius);
  out.state.paused = tasks_.paused();

  // Predicted discs: the current command held over the horizon, the EKF's covariance grown along it.
  out.discs.source_id = p_.id;
  out.discs.kind = msg::SourceKind::Robot;
  out.discs.t0_ns = nowNs;
  out.discs.dt = static_cast<float>(p_.predictionDt);
  DiscPredictionParams prediction;
  prediction.radius = p_.radius;
  prediction.dt = p_.predictionDt;
  prediction.horizonS = p_.predictionHorizonS;
  if (plausible) {
    out.discs.discs = predictDiscs(pose, P, v, w, prediction);
  }
  if (auto r = tasks_.takeReport()) {
    out.status =
        msg::TaskStatus{p_.id, r->task, r->revision, wireState(r->stage), r->progress, r->reason, r->stampNs};
  }
  if (reserved_) {
    out.traffic = trafficProgress(nowNs);
  }
}

}  // namespace fleet::agent
