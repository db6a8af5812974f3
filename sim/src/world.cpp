#include "fleet/sim/world.hpp"

#include <algorithm>
#include <cmath>
#include <unordered_set>
#include <utility>

#include "fleet/control/diff_drive_kinematics.hpp"
#include "fleet/control/velocity_limits.hpp"
#include "fleet/core/angles.hpp"
#include "world_math.hpp"

namespace fleet::sim {

using world_detail::len;
using world_detail::normal;

namespace {

std::uint64_t splitmix(std::uint64_t& x) {
  std::uint64_t z = (x += 0x9e3779b97f4a7c15ULL);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}
std::uint64_t pairKey(int a, int b) {
  return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(a)) << 32) | static_cast<std::uint32_t>(b);
}

constexpr double kChargeReach = 0.5;  // m from a charging station's pose
constexpr double kStillSpeed = 0.02;  // m/s under which a robot is idle

// Minimum separations are tracked for pairs with a surface gap under this (or near_miss_m if larger);
// a run whose bodies never come that close reports null.
constexpr double kSeparationReach = 2.0;
}  // namespace

World::World(Scenario scenario)
    : sc_(std::move(scenario)),
      hash_({sc_.map.origin.x - 1.0, sc_.map.origin.y - 1.0},
            {sc_.map.origin.x + sc_.map.widthM() + 1.0, sc_.map.origin.y + sc_.map.heightM() + 1.0},
            std::max(2.0, sc_.social.cutoff)) {
  std::uint64_t s = sc_.seed;
  motionRng_.engine.seed(splitmix(s));
  humanRng_.engine.seed(splitmix(s));
  sensorRng_.engine.seed(splitmix(s));
  robots_.resize(sc_.robots.size());
  for (std::size_t i = 0; i < robots_.size(); ++i) {
    robots_[i].pose = sc_.robots[i].start;
    robots_[i].battery = sc_.robots[i].battery.initial;
    robotIds_[sc_.robots[i].id] = static_cast<int>(i);
    maxRadius_ = std::max(maxRadius_, sc_.robots[i].radius);
    sensorEvery_.push_back(
        std::max(1, static_cast<int>(std::lround(1.0 / (sc_.robots[i].sensors.rateHz * sc_.dt)))));
  }
  bumpDepth_.assign(robots_.size(), 0.0);
  timedOut_.assign(robots_.size(), false);
  spawnHumans();
  for (const auto& h : humans_) {
    maxRadius_ = std::max(maxRadius_, h.r);
  }
  rebuildHash();
  updateContacts();
}

std::int64_t World::timeNs() const {
  return static_cast<std::int64_t>(std::llround(static_cast<double>(step_) * sc_.dt * 1e9));
}

int World::robotIndex(const std::string& id) const {
  auto it = robotIds_.find(id);
  return it == robotIds_.end() ? -1 : it->second;
}

std::string World::bodyId(int index) const {
  if (index < 0) {
    return "#shelf";
  }
  const auto i = static_cast<std::size_t>(index);
  return i < robots_.size() ? sc_.robots[i].id : humans_[i - robots_.size()].id;
}
CommandOutcome World::command(const std::string& id, double v, double w) {
  const int i = robotIndex(id);
  if (i < 0) {
    ++counters_.unknownRobot;
    return CommandOutcome::Ignored;
  }
  return command(static_cast<std::size_t>(i), v, w);
}

CommandOutcome World::command(std::size_t i, double v, double w) {
  if (!std::isfinite(v) || !std::isfinite(w)) {
    ++counters_.nanCommands;
    return CommandOutcome::Ignored;
  }
  const auto& lim = sc_.robots[i].limits;
  RobotBody& r = robots_[i];
  r.command = {v, w};
  r.commandTime = time();
  if (v > lim.vMax || v < lim.vMin || std::abs(w) > lim.omegaMax) {
    ++counters_.clampedCommands;
    return CommandOutcome::Clamped;
  }
  return CommandOutcome::Accepted;
}

void World::setLabel(std::size_t robot, std::string mode, std::string task, std::string activity) {
  robots_[robot].mode = std::move(mode);
  robots_[robot].task = std::move(task);
  robots_[robot].activity = std::move(activity);
}

void World::setChargeSwitch(std::size_t robot, bool on) {
  robots_[robot].switchedCharging = true;
  robots_[robot].chargeSwitch = on;
}

bool World::atCharger(std::size_t robot) const {
  const auto& p = robots_[robot].pose;
  return std::any_of(sc_.stations.begin(), sc_.stations.end(), [&](const auto& st) {
    return st.kind == StationKind::Charging && distance(st.pose, p) < kChargeReach;
  });
}

void World::advance() {
  stepHumans();  // reads robot poses of the step start; writes humans after robots are done below
  stepRobots();
  ++step_;
  rebuildHash();
  updateContacts();
}

void World::stepRobots() {
  const double dt = sc_.dt;
  const double now = time();
  for (std::size_t i = 0; i < robots_.size(); ++i) {
    RobotBody& r = robots_[i];
    const RobotSpec& spec = sc_.robots[i];
    control::Twist desired = r.command;
    const bool stale = now - r.commandTime > spec.commandTimeout + 1e-9;
    if (stale) {
      desired = {};
      if (!timedOut_[i] && std::isfinite(r.commandTime)) {
        ++counters_.timeouts;
      }
    }
    timedOut_[i] = stale;
    if (r.battery <= 0.0) {
      desired = {};
    }
    const auto lim = control::applyLimits(spec.limits, desired, r.twist, dt);
    control::Twist t = lim.twist;
    // Wheel slip: each wheel executes its speed with a small relative error.
    const double half = 0.5 * spec.wheelBase;
    double vl = (t.v - t.omega * half) * (1.0 + normal(motionRng_, spec.noise.slipSigma));
    double vr = (t.v + t.omega * half) * (1.0 + normal(motionRng_, spec.noise.slipSigma));
    const control::Twist executed{0.5 * (vl + vr), (vr - vl) / spec.wheelBase};
    const Pose2 next = control::DiffDriveKinematics::integrateExact(r.pose, executed, dt);
    bumpDepth_[i] = 0.0;
    const double before = discGridPenetration(sc_.map, r.pose.position(), spec.radius);
    const double after = discGridPenetration(sc_.map, next.position(), spec.radius);
    if (after > 0.0 && after > before + 1e-12) {
      // The shelf stops the robot where it touches (bisection on the fraction of the step), wheels
      // stalled; the attempted overlap is the contact depth.
      bumpDepth_[i] = after;
      ++r.bumps;
      double lo = 0.0;
      double hi = 1.0;
      for (int it = 0; it < 30; ++it) {
        const double mid = 0.5 * (lo + hi);
        const Pose2 q = control::DiffDriveKinematics::integrateExact(r.pose, executed, dt * mid);
        (discGridPenetration(sc_.map, q.position(), spec.radius) > before ? hi : lo) = mid;
      }
      r.pose = control::DiffDriveKinematics::integrateExact(r.pose, executed, dt * lo);
      vl *= lo;
      vr *= lo;
      r.twist = {};
    } else {
      r.pose = next;
      r.twist = t;
    }
    const double dsl = vl * dt;
    const double dsr = vr * dt;
    const double measuredLeft = dsl * (1.0 + normal(motionRng_, spec.noise.odomSigma));
    const double measuredRight = dsr * (1.0 + normal(motionRng_, spec.noise.odomSigma));
    r.odomLeft += measuredLeft;
    r.odomRight += measuredRight;
    r.odomLeftTotal += measuredLeft;
    r.odomRightTotal += measuredRight;
    const double moved = std::abs(0.5 * (dsl + dsr));
    r.distance += moved;
    if (std::abs(r.twist.v) < kStillSpeed && std::abs(r.twist.omega) < kStillSpeed) {
      r.idleS += dt;
    }
    r.charging = std::abs(r.twist.v) < kStillSpeed && (!r.switchedCharging || r.chargeSwitch) && atCharger(i);
    if (r.charging) {
      r.battery = std::min(1.0, r.battery + spec.battery.chargePerS * dt);
    } else {
      r.battery = std::max(0.0, r.battery - spec.battery.drainIdlePerS * dt - spec.battery.drainPerM * moved);
    }
  }
}
void World::rebuildHash() {
  positions_.resize(robots_.size() + humans_.size());
  radii_.resize(positions_.size());
  for (std::size_t i = 0; i < robots_.size(); ++i) {
    positions_[i] = robots_[i].pose.position();
    radii_[i] = sc_.robots[i].radius;
  }
  for (std::size_t i = 0; i < humans_.size(); ++i) {
    positions_[robots_.size() + i] = humans_[i].p;
    radii_[robots_.size() + i] = humans_[i].r;
  }
  hash_.build(positions_);
}

void World::updateContacts() {
  contacts_.clear();
  std::unordered_set<std::uint64_t> touching;
  std::unordered_set<std::uint64_t> near;
  const std::size_t nr = robots_.size();
  for (std::size_t i = 0; i < nr; ++i) {
    const Vec2 p = positions_[i];
    const double ri = radii_[i];
    const double sepReach = std::max(sc_.nearMiss, kSeparationReach);
    const double reach = ri + maxRadius_ + sepReach;
    std::vector<std::pair<int, double>> hits;
    hash_.forEachNear(p, reach, [&](int j) {
      const auto ju = static_cast<std::size_t>(j);
      if (ju < nr && ju <= i) {
        return;  // each robot pair once
      }
      const double gap = len(p - positions_[ju]) - ri - radii_[ju];
      if (gap < sepReach) {
        hits.emplace_back(j, gap);
      }
    });
    std::sort(hits.begin(), hits.end());
    for (const auto& [j, gap] : hits) {
      const bool human = static_cast<std::size_t>(j) >= nr;
      double& minSep = human ? metrics_.minSepRobotHuman : metrics_.minSepRobotRobot;
      minSep = std::min(minSep, gap);
      const std::uint64_t key = pairKey(static_cast<int>(i), j);
      if (gap < 0.0) {
        contacts_.push_back({static_cast<int>(i), j, -gap});
        touching.insert(key);
        if (!touching_.count(key)) {
          ++(human ? metrics_.robotHumanContacts : metrics_.robotRobotContacts);
        }
      } else if (gap < sc_.nearMiss) {
        near.insert(key);
        if (!near_.count(key) && !touching_.count(key)) {
          ++(human ? metrics_.nearMissRobotHuman : metrics_.nearMissRobotRobot);
        }
      }
    }
    double wd = 0.0;
    Vec2 away;
    // Shelves are everywhere in a warehouse: their clearance is tracked only up to 0.5 m (or the
    // near-miss distance) to keep the cell scan small.
    if (nearestBlocked(sc_.map, p, ri + std::max(sc_.nearMiss, 0.5), wd, away)) {
      metrics_.minSepRobotShelf = std::min(metrics_.minSepRobotShelf, wd - ri);
    }
    const double depth = std::max(bumpDepth_[i], discGridPenetration(sc_.map, p, ri));
    const std::uint64_t key = pairKey(static_cast<int>(i), -1);
    if (depth > 0.0) {
      contacts_.push_back({static_cast<int>(i), -1, depth});
      metrics_.minSepRobotShelf = std::min(metrics_.minSepRobotShelf, -depth);
      touching.insert(key);
      if (!touching_.count(key)) {
        ++metrics_.robotShelfContacts;
      }
    }
  }
  if (!contacts_.empty()) {
    ++metrics_.contactSteps;
  }
  touching_ = std::move(touching);
  near_ = std::move(near);
}
}  // namespace fleet::sim
