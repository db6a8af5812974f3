#include "agent.hpp"

#include <algorithm>
#include <cmath>

#include "fleet/avoidance/safety_layer.hpp"
#include "fleet/core/clock.hpp"
#include "fleet/planning/astar.hpp"
#include "risk_astar.hpp"

#include <stdexcept>

namespace fleet::agent {
namespace {

estimation::PoseEkf makeEkf(const AgentParams& p) {
  estimation::EkfParams ep;
  ep.wheel_base = p.wheelBase;
  ep.compass_variance = 0.02 * 0.02;
  ep.bearing_variance = 0.01 * 0.01;
  Eigen::Matrix3d p0 = Eigen::Matrix3d::Zero();
  p0.diagonal() << 0.01, 0.01, 0.001;
  auto e = estimation::PoseEkf::create(ep, p.start, p0);
  return std::move(*e);  // parameters are constants above: cannot fail
}

control::PathFollowerParams followerParams() {
  control::PathFollowerParams fp;
  fp.lookahead = 0.5;
  fp.goal_tolerance_xy = 0.15;
  fp.goal_tolerance_theta = 0.25;
  return fp;
}

}  // namespace

std::shared_ptr<const planning::OccupancyGrid> inflate(const planning::OccupancyGrid& raw, double radius) {
  return std::make_shared<const planning::OccupancyGrid>(raw.inflated(radius));
}

Agent::Agent(AgentParams params, std::shared_ptr<const planning::OccupancyGrid> grid,
             std::shared_ptr<const planning::OccupancyGrid> raw)
    : p_(std::move(params)),
      grid_(std::move(grid)),
      raw_(std::move(raw)),
      ekf_(makeEkf(p_)),
      follower_(followerParams()) {
  if (p_.localPlanner != "follow") {
    auto inner = avoidance::makePlanner(p_.localPlanner);
    if (!inner) {
      throw std::invalid_argument("local planner: " + inner.error().message);
    }
    planner_ = std::make_unique<avoidance::SafePlanner>(std::move(*inner));
  }
}

control::Twist Agent::planLocal(bool& reached, bool& blocked) {
  const Pose2 pose = ekf_.pose();
  // Drop the path points already passed: keep from the one nearest to the robot.
  std::size_t nearest = 0;
  for (std::size_t i = 0; i < path_.size() && i < 40; ++i) {
    if (distance(path_[i], pose.position()) < distance(path_[nearest], pose.position())) {
      nearest = i;
    }
  }
  path_.erase(path_.begin(), path_.begin() + static_cast<std::ptrdiff_t>(nearest));
  std::vector<Vec2> scan;
  std::vector<avoidance::MovingDisc> discs;
  if (haveFrame_) {
    for (std::size_t i = 0; i < frame_.ranges.size(); ++i) {
      const double range = static_cast<double>(frame_.ranges[i]);
      if (range < static_cast<double>(frame_.range_max) && range < 3.0) {
        const double a = static_cast<double>(frame_.angle_min) +
                         static_cast<double>(i) * static_cast<double>(frame_.angle_increment);
        scan.push_back(pose.transform({range * std::cos(a), range * std::sin(a)}));
      }
    }
    for (const auto& d : frame_.detections) {
      discs.push_back({pose.transform({static_cast<double>(d.x), static_cast<double>(d.y)}),
                       {},
                       static_cast<double>(d.r)});
    }
  }
  avoidance::LocalView view;
  view.robot = {pose, {v_, w_}, p_.radius};
  view.path = path_;
  view.scan = scan;
  view.discs = discs;
  view.limits = p_.limits;
  view.dt = 0.1;
  view.goal_tolerance = 0.15;
  if (risk_) {
    view.risk = [r = risk_](Vec2 q) { return r->at(q); };
  }
  const auto cmd = planner_->plan(view);
  reached = cmd.status == avoidance::PlanStatus::kGoalReached || distance(pose, goals_[goal_].pose) < 0.15;
  blocked = cmd.status == avoidance::PlanStatus::kBlocked ||
            (cmd.overruled && std::abs(cmd.twist.v) < 0.05 && std::abs(cmd.twist.omega) < 0.05);
  return cmd.twist;
}

void Agent::onFrame(const msg::SensorFrame& f) {
  if (ekf_.predict(f.ds_left, f.ds_right) != estimation::UpdateStatus::kAccepted) {
    ++rejected_;
  }
  if (f.compass_valid && ekf_.updateCompass(f.compass) != estimation::UpdateStatus::kAccepted) {
    ++rejected_;
  }
  for (const auto& lb : f.landmarks) {
    for (const auto& [id, pos] : p_.landmarks) {
      if (id == lb.id &&
          ekf_.updateBearing(pos, static_cast<double>(lb.bearing)) != estimation::UpdateStatus::kAccepted) {
        ++rejected_;
      }
    }
  }
  if (std::isfinite(f.battery)) {
    battery_ = static_cast<double>(f.battery);
  }
  frame_ = f;
  haveFrame_ = true;
  frameSinceStep_ = true;
}

void Agent::onOtherRobot(const msg::RobotState& s) {
  if (s.robot_id == p_.id || !s.pose.isFinite()) {
    return;
  }
  for (auto& [id, pos] : others_) {
    if (id == s.robot_id) {
      pos = s.pose.position();
      return;
    }
  }
  others_.emplace_back(s.robot_id, s.pose.position());
}

void Agent::onAssignment(const msg::TaskAssignment& a) {
  if (a.robot_id != p_.id || (a.revision == revision_ && a.task_id == task_)) {
    return;  // not ours, or the same order again (transient-local re-delivery)
  }
  revision_ = a.revision;
  if (a.task_id.empty()) {
    task_.clear();
    goals_.clear();
    phase_ = Phase::Idle;
    return;
  }
  if (a.task_id == task_ && a.goals == goals_) {
    return;  // re-published after a manager restart: keep going
  }
  task_ = a.task_id;
  goals_ = a.goals;
  goal_ = 0;
  reported_ = msg::TaskState::Assigned;
  phase_ = Phase::Idle;  // started on the next step, which knows the time
}

msg::TaskState Agent::taskStateFor(std::size_t goalIndex, bool dwelling) const {
  const auto action = goals_[goalIndex].action;
  if (dwelling) {
    if (action == msg::GoalAction::Load) {
      return msg::TaskState::Loading;
    }
    if (action == msg::GoalAction::Unload) {
      return msg::TaskState::Unloading;
    }
  }
  for (std::size_t i = 0; i < goalIndex; ++i) {
    if (goals_[i].action == msg::GoalAction::Load) {
      return msg::TaskState::Delivering;
    }
  }
  return msg::TaskState::EnRoute;
}

void Agent::startGoal(std::int64_t nowNs, std::optional<Vec2> avoid) {
  const auto& g = goals_[goal_];
  planning::AStarPlanner plainAstar;
  // Lanes and risk together: the risk map's probability scales each cell's cost as in risk_astar.
  planning::CellCostFactor riskFactor;
  if (risk_) {
    riskFactor = [r = risk_, w = p_.riskWeightGlobal, gr = grid_](planning::Cell c) {
      return 1.0 + w * r->at(gr->cellCenter(c));
    };
  }
  planning::LanePlanner lanePlanner(p_.lanes, riskFactor);
  planning::GlobalPlanner& astar = p_.lanes ? static_cast<planning::GlobalPlanner&>(lanePlanner)
                                            : static_cast<planning::GlobalPlanner&>(plainAstar);
  Expected<planning::Path> path = unexpected("no_path", "not planned");
  if (avoid) {
    planning::OccupancyGrid detour = *grid_;
    const double res = detour.resolution();
    const int reach = static_cast<int>(std::ceil(0.9 / res));
    if (const auto c = detour.cellAt(*avoid)) {
      for (int dy = -reach; dy <= reach; ++dy) {
        for (int dx = -reach; dx <= reach; ++dx) {
          const planning::Cell q{c->x + dx, c->y + dy};
          if (detour.inside(q) && distance(detour.cellCenter(q), *avoid) <= 0.9) {
            detour.setBlocked(q);
          }
        }
      }
    }
    path = astar.plan(detour, ekf_.pose(), g.pose);
    if (!path) {
      return;  // no way around: keep the current path and wait
    }
  } else if (risk_ && !p_.lanes) {
    RiskAStarPlanner riskAware([r = risk_](Vec2 q) { return r->at(q); }, p_.riskWeightGlobal);
    path = riskAware.plan(*grid_, ekf_.pose(), g.pose);
  } else {
    path = astar.plan(*grid_, ekf_.pose(), g.pose);
  }
  if (!path) {
    path = astar.plan(*raw_, ekf_.pose(), g.pose);  // a start or goal hugging a shelf
  }
  if (!path || !follower_.setPath(path->poses)) {
    finishTask(msg::TaskState::Failed,
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
  phase_ = Phase::Driving;
  phaseStartNs_ = nowNs;
  lastProgressNs_ = nowNs;
  blockedSinceNs_ = -1;
  detoured_ = avoid.has_value();
  const auto st = taskStateFor(goal_, false);
  if (st != reported_) {
    reported_ = st;
    pendingStatus_ = msg::TaskStatus{
        p_.id, task_, revision_, st, static_cast<float>(goal_) / static_cast<float>(goals_.size()),
        "",    nowNs};
  }
}

void Agent::finishTask(msg::TaskState final, const std::string& reason, std::int64_t nowNs) {
  pendingStatus_ = msg::TaskStatus{
      p_.id, task_, revision_, final, final == msg::TaskState::Done ? 1.0f : 0.0f, reason.substr(0, 255),
      nowNs};
  task_.clear();
  goals_.clear();
  phase_ = Phase::Idle;
}

double Agent::clearSpeed(double v, bool& blockedByRobot, std::string& blocker) const {
  blockPoint_.reset();
  if (!haveFrame_ || v <= 0.0) {
    return v;
  }
  double allowed = v;
  auto limit = [&](double gap) {
    allowed = std::min(allowed, std::max(0.0, (gap - p_.stopGap) / p_.headway));
  };
  for (const auto& d : frame_.detections) {
    const double x = static_cast<double>(d.x);
    const double y = static_cast<double>(d.y);
    const double r = static_cast<double>(d.r);
    if (x <= 0.0 || std::abs(y) > p_.radius + r + 0.05) {
      continue;  // not in the corridor the robot sweeps
    }
    const double gap = std::hypot(x, y) - p_.radius - r;
    const double before = allowed;
    limit(gap);
    if (allowed < before) {
      blockPoint_ = ekf_.pose().transform({x, y});
    }
    if (allowed < before && allowed < 0.05) {
      blockedByRobot = d.kind == msg::SourceKind::Robot;
      blocker = blockedByRobot ? "robot" : "human";
      if (blockedByRobot) {
        // Name the robot: the known robot nearest to where the detection is.
        const Vec2 at = ekf_.pose().transform({x, y});
        double best = 1.0;
        for (const auto& [id, pos] : others_) {
          if (distance(pos, at) < best) {
            best = distance(pos, at);
            blocker = id;
          }
        }
      }
    }
  }
  // Range readings: every point that lies in the corridor the robot sweeps ahead limits the speed.
  const int n = static_cast<int>(frame_.ranges.size());
  for (int i = 0; i < n; ++i) {
    const double range = static_cast<double>(frame_.ranges[static_cast<std::size_t>(i)]);
    if (!(range < static_cast<double>(frame_.range_max))) {
      continue;
    }
    const double a = static_cast<double>(frame_.angle_min) + i * static_cast<double>(frame_.angle_increment);
    const double ahead = range * std::cos(a);
    if (ahead > 0.0 && std::abs(range * std::sin(a)) < p_.radius + 0.05) {
      const double before = allowed;
      limit(ahead - p_.radius);
      if (allowed < before) {
        blockPoint_ = ekf_.pose().transform({ahead, range * std::sin(a)});
      }
    }
  }
  return allowed;
}

bool Agent::rearClear() const {
  if (!haveFrame_) {
    return false;
  }
  const double keep = p_.radius + 0.25;
  for (const auto& d : frame_.detections) {
    const double x = static_cast<double>(d.x);
    const double y = static_cast<double>(d.y);
    if (x < 0.0 && std::abs(y) < p_.radius + static_cast<double>(d.r) + 0.05 &&
        -x - static_cast<double>(d.r) < keep) {
      return false;
    }
  }
  const int n = static_cast<int>(frame_.ranges.size());
  for (int i = 0; i < n; ++i) {
    const double range = static_cast<double>(frame_.ranges[static_cast<std::size_t>(i)]);
    const double a = static_cast<double>(frame_.angle_min) + i * static_cast<double>(frame_.angle_increment);
    const double ahead = range * std::cos(a);
    if (range < static_cast<double>(frame_.range_max) && ahead < 0.0 &&
        std::abs(range * std::sin(a)) < p_.radius + 0.05 && -ahead < keep) {
      return false;
    }
  }
  return true;
}

void Agent::enterDwell(std::int64_t nowNs) {
  phase_ = Phase::Dwelling;
  phaseStartNs_ = nowNs;
  const auto st = taskStateFor(goal_, true);
  if (st != reported_ && (st == msg::TaskState::Loading || st == msg::TaskState::Unloading)) {
    reported_ = st;
    pendingStatus_ = msg::TaskStatus{
        p_.id, task_, revision_, st, static_cast<float>(goal_) / static_cast<float>(goals_.size()),
        "",    nowNs};
  }
}

void Agent::onStandoff(std::int64_t nowNs, bool byRobot, const std::string& blocker, double& v, double& w) {
  if (blockedSinceNs_ < 0) {
    blockedSinceNs_ = nowNs;
  }
  const double blockedS = nsToSec(nowNs - blockedSinceNs_);
  // A person who does not step aside, or two robots face to face (the larger id yields): back off
  // if nothing is behind, then try another way around, rather than wait forever.
  const bool yields = byRobot ? (blocker != "robot" && p_.id > blocker) : true;
  if (blockedS > p_.blockedBackoffS && yields && rearClear()) {
    phase_ = Phase::BackingOff;
    phaseStartNs_ = nowNs;
  } else if (blockedS > 2.0 * p_.blockedBackoffS && blockPoint_ &&
             (lastDetourNs_ < 0 || nsToSec(nowNs - lastDetourNs_) > 2.0 * p_.blockedBackoffS)) {
    // Try a way around what stands in the way, again every while: in a queue of robots nobody
    // can back off, and the one ahead may have moved aside since the last attempt.
    lastDetourNs_ = nowNs;
    startGoal(nowNs, blockPoint_);
    detoured_ = true;
  } else if (blockedS > p_.blockedFailS) {
    finishTask(msg::TaskState::Failed,
               "blocked by " + (blocker.empty() ? std::string("an obstacle") : blocker) + " for " +
                   std::to_string(static_cast<int>(p_.blockedFailS)) + " s",
               nowNs);
    v = 0;
    w = 0;
  }
}

bool Agent::sensorStreamLost(std::int64_t nowNs) {
  if (frameSinceStep_ || lastFrameNs_ < 0) {
    // The first step starts the count: a robot that never gets a frame is reported too.
    lastFrameNs_ = nowNs;
  }
  const bool fresh = frameSinceStep_;
  frameSinceStep_ = false;
  const bool lost = !fresh && nsToSec(nowNs - lastFrameNs_) > p_.sensorTimeoutS;
  if (lost == sensorLost_) {
    return lost;
  }
  sensorLost_ = lost;
  std::string reason;
  if (lost) {
    lostSinceNs_ = nowNs;
    reason = "sensor stream lost: no SensorFrame for " + std::to_string(nsToSec(nowNs - lastFrameNs_)) + " s";
  } else {
    // The outage is not time spent blocked or without progress.
    const std::int64_t outage = nowNs - lostSinceNs_;
    if (blockedSinceNs_ >= 0) {
      blockedSinceNs_ += outage;
    }
    lastProgressNs_ += outage;
    if (planner_) {
      planner_->reset();
    }
  }
  if (!task_.empty()) {
    const float progress =
        goals_.empty() ? 0.0f : static_cast<float>(goal_) / static_cast<float>(goals_.size());
    pendingStatus_ = msg::TaskStatus{p_.id, task_, revision_, reported_, progress, reason, nowNs};
  }
  return lost;
}

AgentOutput Agent::step(std::int64_t nowNs, double dt) {
  if (!sensorStreamLost(nowNs)) {
    return drive(nowNs, dt);
  }
  // Blind: hold still and say why; the task is kept and resumes when frames come back.
  AgentOutput out;
  v_ = 0.0;
  w_ = 0.0;
  report(out, nowNs, 0.0, 0.0, msg::RobotMode::Fault);
  return out;
}

AgentOutput Agent::drive(std::int64_t nowNs, double dt) {
  AgentOutput out;
  double v = 0.0;
  double w = 0.0;
  msg::RobotMode mode = msg::RobotMode::Idle;
  if (!task_.empty() && phase_ == Phase::Idle) {
    startGoal(nowNs);
  }
  if (phase_ == Phase::Driving && planner_) {
    bool reached = false;
    bool blocked = false;
    const auto tw = planLocal(reached, blocked);
    if (reached) {
      enterDwell(nowNs);
    } else {
      v = tw.v;
      w = tw.omega;
      mode = blocked ? msg::RobotMode::Waiting : msg::RobotMode::Moving;
      if (blocked) {
        bool byRobot = false;
        std::string blocker;
        (void)clearSpeed(0.5, byRobot, blocker);  // who is in the way
        onStandoff(nowNs, byRobot, blocker, v, w);
      } else {
        blockedSinceNs_ = -1;
      }
    }
  } else if (phase_ == Phase::Driving) {
    auto r = follower_.step(ekf_.pose());
    if (!r) {
      finishTask(msg::TaskState::Failed, "path follower: " + r.error().message, nowNs);
    } else if (r->goal_reached || (r->final_approach && distance(ekf_.pose(), goals_[goal_].pose) < 0.15)) {
      enterDwell(nowNs);
    } else {
      v = std::clamp(r->cmd.v, -0.3, p_.vMax);
      w = std::clamp(r->cmd.omega, -p_.wMax, p_.wMax);
      // Far off the carrot's bearing: turn in place first, so the robot does not sweep an arc
      // through its neighbours (robots park side by side) or into shelf ends.
      const Vec2 toCarrot = r->target.position() - ekf_.pose().position();
      const double bearing = angleDiff(std::atan2(toCarrot.y, toCarrot.x), ekf_.pose().theta);
      if (!r->final_approach && toCarrot.norm() > 0.05 && std::abs(bearing) > 0.7) {
        v = 0.0;
        w = std::clamp(2.0 * bearing, -p_.wMax, p_.wMax);
      }
      mode = msg::RobotMode::Moving;
      bool byRobot = false;
      std::string blocker;
      const double wanted = v;
      const double allowed = clearSpeed(v, byRobot, blocker);
      if (allowed < v - 1e-9) {
        // Keep the curvature while slowing, so the robot stays on its path.
        if (std::abs(v) > 1e-9) {
          w *= allowed / v;
        }
        v = allowed;
      }
      if (wanted > 0.1 && allowed < 0.05) {
        mode = msg::RobotMode::Waiting;
        onStandoff(nowNs, byRobot, blocker, v, w);
      } else {
        blockedSinceNs_ = -1;
      }
    }
  } else if (phase_ == Phase::Dwelling) {
    mode =
        goals_[goal_].action == msg::GoalAction::Charge ? msg::RobotMode::Charging : msg::RobotMode::Loading;
    if (nsToSec(nowNs - phaseStartNs_) >= goals_[goal_].duration_s) {
      ++goal_;
      if (goal_ >= goals_.size()) {
        finishTask(msg::TaskState::Done, "", nowNs);
      } else {
        startGoal(nowNs);
      }
    }
  } else if (phase_ == Phase::BackingOff) {
    mode = msg::RobotMode::Waiting;
    v = rearClear() ? -0.2 : 0.0;
    if (nsToSec(nowNs - phaseStartNs_) > 1.5) {
      startGoal(nowNs);  // replan from where it stands
    }
  }
  v_ = v;
  w_ = w;
  (void)dt;
  report(out, nowNs, v, w, mode);
  return out;
}

void Agent::report(AgentOutput& out, std::int64_t nowNs, double v, double w, msg::RobotMode mode) {
  const Pose2 pose = ekf_.pose();
  out.command = {p_.id, v, w, nowNs, 0};
  out.state.robot_id = p_.id;
  out.state.stamp_ns = nowNs;
  out.state.pose = pose;
  const auto& P = ekf_.covariance();
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      out.state.covariance[static_cast<std::size_t>(3 * i + j)] = P(i, j);
    }
  }
  out.state.v = v;
  out.state.w = w;
  out.state.mode = mode;
  out.state.battery = static_cast<float>(battery_);
  out.state.task_id = task_;
  out.state.radius = static_cast<float>(p_.radius);

  // Predicted discs: the current command held over the horizon, σ growing from the EKF's.
  out.discs.source_id = p_.id;
  out.discs.kind = msg::SourceKind::Robot;
  out.discs.t0_ns = nowNs;
  out.discs.dt = static_cast<float>(p_.predictionDt);
  const double sigma0 = std::sqrt(std::max(P(0, 0), P(1, 1)));
  Pose2 q = pose;
  const int steps = static_cast<int>(p_.predictionHorizonS / p_.predictionDt) + 1;
  for (int k = 0; k < steps; ++k) {
    const double t = k * p_.predictionDt;
    out.discs.discs.push_back({static_cast<float>(q.x), static_cast<float>(q.y),
                               static_cast<float>(p_.radius), static_cast<float>(sigma0 + 0.1 * t)});
    q = {q.x + v * std::cos(q.theta) * p_.predictionDt, q.y + v * std::sin(q.theta) * p_.predictionDt,
         wrapAngle(q.theta + w * p_.predictionDt)};
  }
  out.status = std::move(pendingStatus_);
  pendingStatus_.reset();
}

}  // namespace fleet::agent
