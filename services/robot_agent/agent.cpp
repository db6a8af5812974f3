#include "agent.hpp"

#include <algorithm>
#include <cmath>

#include "agent_wire.hpp"
#include "disc_prediction.hpp"
#include "fleet/avoidance/rotation_shim.hpp"
#include "fleet/avoidance/safety_layer.hpp"
#include "fleet/core/clock.hpp"
#include "map_faces.hpp"

#include <stdexcept>

namespace fleet::agent {
namespace {

LocalizerParams localizerParams(const AgentParams& p) {
  LocalizerParams lp;
  lp.start = p.resumeAt.value_or(p.start);
  if (p.resumeAt && p.resumeWheels) {
    // The roll since the pose was written comes from the first reading's wheel totals.
    lp.startWheels = p.resumeWheels;
    lp.startVarianceXY = kResumeWheelsVarianceXY;
    lp.startVarianceTheta = kResumeWheelsVarianceTheta;
  } else if (p.resumeAt) {
    // It may have rolled on after its process stopped (its last command held for the driver's
    // timeout, then braking) and since the pose was written.
    lp.startVarianceXY = kResumeVarianceXY;
    lp.startVarianceTheta = kResumeVarianceTheta;
  }
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

/// DWA's rollout at cruise ends this fraction of the way to its carrot (see
/// the constructor).
constexpr double kRolloutToCarrot = 0.8;
/// A progress report at least this often [s], whatever changed.
constexpr double kHeartbeatS = 1.0;

}  // namespace

avoidance::DwaParams agentDwaDefaults() {
  avoidance::DwaParams p;
  p.lookahead = 0.8;
  return p;
}

Agent::Agent(AgentParams params, std::shared_ptr<const planning::OccupancyGrid> raw)
    : p_(std::move(params)),
      raw_(std::move(raw)),
      localizer_(localizerParams(p_)),
      lastPlausiblePose_(p_.resumeAt.value_or(p_.start)),
      gate_(GateParams{p_.radius, p_.stopGap, p_.headway, p_.robotStopGap, p_.limits, p_.speedLimit, false}),
      progress_(p_.progress),
      follow_(FollowerParams{p_.radius, p_.vMax, p_.wMax, p_.limits}, raw_, progress_) {
  if (p_.localPlanner != "follow") {
    using PlannerPtr = Expected<std::unique_ptr<avoidance::LocalPlanner>>;
    const bool stepping = p_.localPlanner == "risk_stepping" || p_.localPlanner == "risk_stepping_weighted";
    auto steppingParams = p_.riskStepping;
    if (p_.localPlanner == "risk_stepping_weighted") {
      steppingParams.rule = avoidance::SteppingRule::kWeighted;
    }
    auto dwa = p_.dwa;
    {
      // DWA scores progress towards a carrot `lookahead` along the path over a `simTime` rollout,
      // which peaks where the rollout ends on the carrot: 0.8 m over 1.7 s is 0.47 m/s, and a lone
      // robot drove 72 % of its time at 0.4-0.6 m/s. A longer carrot cut shelf corners off the
      // base (a robot stood at one for good), so the rollout is shortened instead: at cruise it
      // ends a fifth short of the carrot. (Ending exactly on it, the heading term's bearing from
      // the rollout's end to the carrot swung sideways for a centimetre off the base, and a lone
      // robot drove 0.6-0.75 m/s for 40 % of its time: 1.39-1.42x its kinematic bound, 1.23-1.26x
      // with this and faster docking, docs/benchmarks.md. The clearance term looks 2 m ahead.)
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
    safety.slowForStatic = false;
    planner_ = std::make_unique<avoidance::SafePlanner>(std::move(*inner), safety);
  }
}

control::Twist Agent::planLocal(const std::vector<Vec2>& window, bool& blocked) {
  const Pose2 pose = localizer_.pose();
  // Drop the window's points already passed: keep from the one nearest to the robot.
  std::size_t nearest = 0;
  for (std::size_t i = 0; i < window.size() && i < 40; ++i) {
    if (distance(window[i], pose.position()) < distance(window[nearest], pose.position())) {
      nearest = i;
    }
  }
  const std::vector<Vec2> path(window.begin() + static_cast<std::ptrdiff_t>(nearest), window.end());
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
  view.path = path;
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

GateView Agent::gateView(const std::vector<Vec2>& route, bool docking) const {
  return {localizer_.perception(), others_, *raw_, {v_, w_}, docking, route.empty() ? nullptr : &route};
}

bool Agent::heldUp(const std::vector<Vec2>& route, bool docking, double& v, double& w, Blocker& blocker) {
  return gate_.heldUp(gateView(route, docking), v, w, blocker).held;
}

double Agent::clearSpeed(const std::vector<Vec2>& route, bool docking, double v, Blocker& blocker) {
  return gate_.clearSpeed(gateView(route, docking), v, blocker).speed;
}

bool Agent::knowsRobot(const std::string& id) const {
  return std::any_of(others_.begin(), others_.end(), [&](const OtherRobot& o) { return o.id == id; });
}

void Agent::onFrame(const msg::SensorFrame& f) {
  localizer_.onReading(readingOf(f));
  if (std::isfinite(f.battery)) {
    battery_ = static_cast<double>(f.battery);
  }
}

std::optional<OtherRobot> Agent::otherOf(const msg::RobotState& s) {
  if (!s.pose.isFinite()) {
    return std::nullopt;
  }
  return OtherRobot{s.robot_id,
                    s.pose.position(),
                    modeOf(s.mode),
                    !s.task_id.empty(),
                    Vec2{std::cos(s.pose.theta), std::sin(s.pose.theta)} * s.v,
                    s.pose.theta,
                    s.stamp_ns};
}

void Agent::onOtherRobot(const msg::RobotState& s) {
  if (s.robot_id == p_.id) {
    return;
  }
  if (const auto o = otherOf(s)) {
    onOtherRobot(slotOf_.try_emplace(s.robot_id, slotOf_.size()).first->second, *o);
  }
}

void Agent::onOtherRobot(std::size_t slot, const OtherRobot& o) {
  // Every robot's state reaches every agent each cycle: its entry by slot, not by walking the list
  // comparing ids (at 300 robots a fifth of an agent process's time).
  if (slot >= entryOf_.size()) {
    entryOf_.resize(slot + 1, -1);
  }
  auto& entry = entryOf_[slot];
  if (entry < 0) {
    if (o.id == p_.id) {
      return;
    }
    entry = static_cast<std::int32_t>(others_.size());
    others_.push_back(o);
    return;
  }
  others_[static_cast<std::size_t>(entry)] = o;
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
      return;
    case TaskRunner::OrderChange::kNewTask:
      progress_.newOrder();
      return;
  }
}

void Agent::refuseAssignment(const msg::TaskAssignment& a, const std::string& why) {
  if (a.robot_id == p_.id) {
    tasks_.refuse(orderOf(a), why);
  }
}

void Agent::onRelease(const msg::TrafficRelease& r) {
  if (r.robot_id != p_.id) {
    follow_.noteForeign();
    return;
  }
  Release rel;
  rel.epoch = r.epoch;
  rel.seq = r.seq;
  rel.endsAtGoal = r.ends_at_goal;
  rel.base.reserve(r.base.size());
  for (const auto& n : r.base) {
    rel.base.push_back({n.node, {n.x, n.y}});
  }
  (void)follow_.offer(rel, localizer_.pose().position());
}

void Agent::endTask(TaskState final, const std::string& reason, std::int64_t nowNs) {
  tasks_.finish(final, reason, nowNs);
  progress_.taskEnded();
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
    // The outage is not time spent without progress.
    progress_.afterOutage(c.outageNs);
    if (planner_) {
      planner_->reset();
    }
  }
  tasks_.notice(reason, nowNs);
  return c.lost;
}

bool Agent::poseDoubtful(std::int64_t nowNs) {
  if (!p_.lineUpdates || !p_.walls || p_.walls->empty()) {
    return false;  // nothing to judge the estimate by
  }
  const LineStats& s = localizer_.lineStats();
  const auto c = poseWatch_.update(nowNs, s.extracted, s.accepted);
  if (c == PoseWatch::Change::kDoubted) {
    doubtedSinceNs_ = nowNs;
    tasks_.notice(poseWatch_.why(), nowNs);
  } else if (c == PoseWatch::Change::kTrusted) {
    // The time it stood is no time without progress.
    progress_.afterOutage(nowNs - doubtedSinceNs_);
    doubtedSinceNs_ = -1;
    if (planner_) {
      planner_->reset();
    }
    tasks_.notice("", nowNs);
  }
  return poseWatch_.doubted();
}

AgentOutput Agent::step(std::int64_t nowNs, double dt) {
  if (!localizer_.plausible()) {
    // The estimate left the world (non-finite, or farther than any map): nothing it would plan or
    // report means anything, and it does not come back by itself. Stop, give the task back and say
    // so, rather than report an idle robot the manager would give the next task.
    AgentOutput out;
    v_ = 0.0;
    w_ = 0.0;
    follow_.holdStill();
    if (tasks_.busy()) {
      endTask(TaskState::Failed, "localization estimate implausible", nowNs);
    }
    report(out, nowNs, 0.0, 0.0, msg::RobotMode::Fault);
    return out;
  }
  if (!sensorStreamLost(nowNs)) {
    if (!poseDoubtful(nowNs)) {
      return drive(nowNs, dt);
    }
    // Its walls are not where the map has them: wherever it drove it would drive from the wrong
    // place. Hold still and say why (the task is kept; the manager's timers decide), and go on when
    // its lines match again.
    AgentOutput out;
    v_ = 0.0;
    w_ = 0.0;
    follow_.holdStill();
    report(out, nowNs, 0.0, 0.0, msg::RobotMode::Fault);
    return out;
  }
  // Blind: hold still and say why; the task is kept and resumes when frames come back.
  AgentOutput out;
  v_ = 0.0;
  w_ = 0.0;
  follow_.holdStill();  // holding, not blocked
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
    follow_.holdStill();  // holding, not blocked
    report(out, nowNs, 0.0, 0.0, msg::RobotMode::Waiting);
    return out;
  }
  if (pausedSinceNs_ >= 0) {
    const std::int64_t held = nowNs - pausedSinceNs_;
    pausedSinceNs_ = -1;
    tasks_.shiftClock(held);
    progress_.afterOutage(held);
    if (planner_) {
      planner_->reset();
    }
  }
  double v = 0.0;
  double w = 0.0;
  msg::RobotMode mode = msg::RobotMode::Idle;
  followRelease(nowNs, dt, v, w, mode);
  watchProgress(nowNs);
  v_ = v;
  w_ = w;
  report(out, nowNs, v, w, mode);
  return out;
}

void Agent::followRelease(std::int64_t nowNs, double dt, double& v, double& w, msg::RobotMode& mode) {
  const Phase before = tasks_.phase();
  const bool charging = before == Phase::Dwelling && tasks_.goal().action == GoalAction::Charge;
  const TaskTick tick = tasks_.tick(nowNs);
  if (tick == TaskTick::kLegBegan) {
    follow_.leaving(localizer_.pose().position());  // from a station, or its parking place
  }
  if (before == Phase::Dwelling) {
    // At work this cycle, also the one in which the dwell ends.
    follow_.atWork();
    mode = charging ? msg::RobotMode::Charging : msg::RobotMode::Loading;
    if (tick != TaskTick::kNone) {
      progress_.newGoal();
    }
    if (tick == TaskTick::kDone) {
      progress_.taskEnded();
    }
    return;
  }
  FollowCycle c;
  c.nowNs = nowNs;
  c.dt = dt;
  c.pose = localizer_.pose();
  c.lastV = v_;
  c.goal = trafficGoal();
  c.busy = tasks_.busy();
  drove_ = follow_.drive(c, *this);
  v = drove_.v;
  w = drove_.w;
  mode = drove_.mode;
  if (drove_.onGoal && tasks_.busy() && tasks_.phase() == Phase::Driving) {
    tasks_.arrive(nowNs);
  }
  follow_.noteStanding(c, drove_);
}

std::optional<TaskGoal> Agent::trafficGoal() const {
  if (tasks_.busy() && tasks_.hasGoal()) {
    return tasks_.goal();
  }
  if (p_.returnHomeS >= 0.0) {
    // Idle: its parking place. The trip home is planned by the traffic manager like any other.
    return TaskGoal{p_.start, "", GoalAction::Park, 0.0};
  }
  return std::nullopt;
}

void Agent::watchProgress(std::int64_t nowNs) {
  ProgressSample sample;
  sample.nowNs = nowNs;
  sample.here = localizer_.pose().position();
  // Progress is along the released nodes (a route on the roadmap may lead away from the goal for a
  // while). Waiting for a release is waiting on another robot, not being stuck: no clock runs.
  sample.travelling = tasks_.phase() == Phase::Driving && follow_.baseAhead();
  sample.goal = follow_.releases().next();
  sample.hasOrder = tasks_.busy();
  sample.driver = drove_.driver;
  sample.held = drove_.held;
  sample.waiting = drove_.waiting;
  switch (progress_.check(sample)) {
    case ProgressVerdict::kFailTask:
      endTask(TaskState::Failed,
              "no progress towards " + tasks_.goal().station + " for " +
                  std::to_string(progress_.failAfterS()) + " s",
              nowNs);
      break;
    case ProgressVerdict::kStalled:
      // A stalled planner hands the drive to the follower for a while (inside the watch); the
      // follower keeps to the released base, and re-planning it is the traffic manager's.
      if (drove_.driver == Driver::kPlanner) {
        ++plannerRecoveries_;
      }
      break;
    case ProgressVerdict::kNone:
      break;
  }
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
  out.state.activity = activity(mode);

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
        msg::TaskStatus{p_.id, r->task, r->revision, r->stage, r->progress, r->reason, r->stampNs, r->step};
  }
  out.traffic = trafficProgress(nowNs);
}

RobotActivity Agent::activity(msg::RobotMode mode) const {
  if (mode == msg::RobotMode::Fault || tasks_.paused()) {
    return RobotActivity::Faulted;  // blind, lost, or held by the operator: not available for work
  }
  if (tasks_.phase() == Phase::Dwelling || mode == msg::RobotMode::Loading ||
      mode == msg::RobotMode::Charging) {
    return mode == msg::RobotMode::Charging ? RobotActivity::Charging : RobotActivity::Dwelling;
  }
  if (!tasks_.busy()) {
    return RobotActivity::NoTask;  // parked, or on its way home
  }
  return drove_.doing;
}

std::optional<msg::TrafficProgress> Agent::trafficProgress(std::int64_t nowNs) {
  msg::TrafficProgress p;
  p.robot_id = p_.id;
  p.epoch = follow_.releases().epoch();
  p.node = follow_.releases().node();
  p.pose = localizer_.pose();
  if (const auto g = trafficGoal()) {
    p.has_goal = true;
    p.goal = g->pose;
    p.goal_station = g->station;
  }
  p.priority = tasks_.priority();
  p.holding = tasks_.phase() == Phase::Dwelling || paused() || localizer_.lost() || poseWatch_.doubted() ||
              follow_.dockingLeg();
  p.blocked = follow_.blocked();
  p.follows = true;
  p.stamp_ns = nowNs;
  const auto& q = lastProgress_;
  const bool changed = !q || q->epoch != p.epoch || q->node != p.node || q->has_goal != p.has_goal ||
                       !(q->goal == p.goal) || q->goal_station != p.goal_station ||
                       q->priority != p.priority || q->holding != p.holding || q->blocked != p.blocked;
  if (!changed && nsToSec(nowNs - q->stamp_ns) < kHeartbeatS) {
    return std::nullopt;
  }
  lastProgress_ = p;
  return p;
}

}  // namespace fleet::agent
