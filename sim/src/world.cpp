#include "fleet/sim/world.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include <utility>

#include "fleet/control/diff_drive_kinematics.hpp"
#include "fleet/control/velocity_limits.hpp"
#include "fleet/core/angles.hpp"
#include "fleet/geometry/grid_raycast.hpp"
#include "fleet/sim/social_force.hpp"

namespace fleet::sim {

namespace {

std::uint64_t splitmix(std::uint64_t& x) {
  std::uint64_t z = (x += 0x9e3779b97f4a7c15ULL);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

// Our own normal/uniform draws: std:: distributions are implementation-defined, these are not.
double uniform01(std::mt19937_64& g) {
  return static_cast<double>(g() >> 11) * 0x1.0p-53;
}
double normal(GaussianStream& g, double sigma) {
  if (sigma <= 0.0) {
    return 0.0;
  }
  if (g.hasSpare) {
    g.hasSpare = false;
    return sigma * g.spare;
  }
  // Box-Muller: both outputs are used, the second one cached for the next draw.
  const double u1 = std::max(uniform01(g.engine), 1e-300);
  const double u2 = uniform01(g.engine);
  const double rho = std::sqrt(-2.0 * std::log(u1));
  g.spare = rho * std::sin(2.0 * kPi * u2);
  g.hasSpare = true;
  return sigma * rho * std::cos(2.0 * kPi * u2);
}
double uniform01(GaussianStream& g) {
  return uniform01(g.engine);
}

// std::hypot (behind Vec2::norm) guards against overflow we cannot have at warehouse scale, at
// several times the cost of a square root; this is the hot path of scans and contacts.
double len(Vec2 v) {
  return std::sqrt(v.squaredNorm());
}

std::uint64_t pairKey(int a, int b) {
  return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(a)) << 32) | static_cast<std::uint32_t>(b);
}

constexpr double kChargeReach = 0.5;     // m from a charging station's pose
constexpr double kStillSpeed = 0.02;     // m/s under which a robot is idle
constexpr double kArrive = 0.6;          // m: a human reached its goal
constexpr double kProgressM = 0.5;       // m: moving less than this in kGiveUpS is being stuck
constexpr double kGiveUpS = 5.0;         // s of being stuck before choosing another goal
constexpr double kBlockingRobotM = 1.0;  // m (surface gap): a robot this close can be what blocks someone
constexpr double kIntoRobotCos = 0.5;    // a way within 60° of a robot's bearing leads into it

// Minimum separations are tracked for pairs with a surface gap under this (or near_miss_m if larger);
// a run whose bodies never come that close reports null.
constexpr double kSeparationReach = 2.0;

// A person wedged against a shelf corner at the keep distance of a robot beside it: the step they
// want, and both slides along the axes, each bring them nearer to one of the two, and the free way
// out can be a wedge of 15° between them (a CI run: 1,400 s frozen there, the robot waiting for
// them). The nearest turned direction that neither penetrates nor crowds more is taken instead.
template <typename Ok>
std::optional<std::pair<Vec2, Vec2>> turnedStep(Vec2 p, Vec2 v, double dt, const Ok& ok) {
  constexpr int kTurns = 18;  // 10° apart on each side
  const double speed = len(v);
  if (speed < 1e-9) {
    return std::nullopt;
  }
  const double a0 = std::atan2(v.y, v.x);
  for (int k = 1; k <= kTurns; ++k) {
    for (const int side : {1, -1}) {
      const double a = a0 + side * k * kPi / kTurns;
      const Vec2 w{speed * std::cos(a), speed * std::sin(a)};
      if (ok(p + w * dt)) {
        return std::pair{p + w * dt, w};
      }
    }
  }
  return std::nullopt;
}

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

int World::fieldFor(Vec2 goal) {
  const int cx = sc_.map.cellX(goal.x);
  const int cy = sc_.map.cellY(goal.y);
  for (std::size_t i = 0; i < fields_.size(); ++i) {
    const Vec2 g = fields_[i].goal();
    if (sc_.map.cellX(g.x) == cx && sc_.map.cellY(g.y) == cy) {
      return static_cast<int>(i);
    }
  }
  fields_.emplace_back(sc_.map, goal);
  return static_cast<int>(fields_.size() - 1);
}

void World::spawnHumans() {
  const GridMap& m = sc_.map;
  auto clear = [&](Vec2 p, double r) {
    if (discGridPenetration(m, p, r + 0.05) > 0.0) {
      return false;
    }
    for (std::size_t i = 0; i < robots_.size(); ++i) {
      if (distance(p, robots_[i].pose.position()) < r + sc_.robots[i].radius + 0.2) {
        return false;
      }
    }
    for (const auto& h : humans_) {
      if (distance(p, h.p) < r + h.r + 0.1) {
        return false;
      }
    }
    return true;
  };
  // Random goals: points of interest and stations, or random free cells when there are none.
  std::vector<Vec2> goals = sc_.pointsOfInterest;
  for (const auto& st : sc_.stations) {
    goals.push_back(st.pose.position());
  }
  if (goals.empty() && (sc_.crowd.count > 0 || !sc_.humans.empty())) {
    for (int tries = 0; tries < 10000 && goals.size() < 16; ++tries) {
      const Vec2 p = m.origin + Vec2{uniform01(humanRng_) * m.widthM(), uniform01(humanRng_) * m.heightM()};
      if (discGridPenetration(m, p, 0.4) <= 0.0) {
        goals.push_back(p);
      }
    }
  }
  for (const auto& g : goals) {
    randomGoals_.push_back(fieldFor(g));
  }
  for (const auto& hs : sc_.humans) {
    HumanBody h;
    h.id = hs.id;
    h.p = hs.start;
    h.v0 = hs.speed;
    h.r = sc_.crowd.radius;
    for (const auto& p : hs.route) {
      h.route.push_back(fieldFor(p));
    }
    h.leader = static_cast<int>(humans_.size());
    humans_.push_back(h);
    if (h.route.empty()) {
      pickGoal(humans_.size() - 1);
    } else {
      humans_.back().field = humans_.back().route[0];
    }
  }
  const CrowdSpec& c = sc_.crowd;
  int made = 0;
  int area = 0;
  while (made < c.count) {
    Area a{m.origin, m.origin + Vec2{m.widthM(), m.heightM()}};
    if (!c.spawnAreas.empty()) {
      a = c.spawnAreas[static_cast<std::size_t>(area++) % c.spawnAreas.size()];
    }
    int leader = -1;
    for (int k = 0; k < c.groupSize && made < c.count; ++k) {
      bool placed = false;
      for (int tries = 0; tries < 200 && !placed; ++tries) {
        Vec2 p;
        if (leader >= 0 && tries < 100) {
          p = humans_[static_cast<std::size_t>(leader)].p +
              Vec2{uniform01(humanRng_) * 2.0 - 1.0, uniform01(humanRng_) * 2.0 - 1.0};
        } else {
          p = a.lo + Vec2{uniform01(humanRng_) * (a.hi.x - a.lo.x), uniform01(humanRng_) * (a.hi.y - a.lo.y)};
        }
        if (!clear(p, c.radius)) {
          continue;
        }
        HumanBody h;
        h.id = "human-" + std::to_string(humans_.size() + 1);
        h.p = p;
        h.r = c.radius;
        h.v0 = std::clamp(c.speedMean + normal(humanRng_, c.speedSd), 0.2, 2.5);
        h.leader = leader >= 0 ? leader : static_cast<int>(humans_.size());
        humans_.push_back(h);
        if (leader < 0) {
          leader = static_cast<int>(humans_.size() - 1);
          pickGoal(humans_.size() - 1);
        } else {
          humans_.back().field = humans_[static_cast<std::size_t>(leader)].field;
        }
        placed = true;
      }
      ++made;  // a human that cannot be placed is dropped, not retried forever
    }
  }
}

void World::pickGoal(std::size_t hi) {
  HumanBody& h = humans_[hi];
  if (!h.route.empty()) {
    h.routeIdx = (h.routeIdx + 1) % h.route.size();
    h.field = h.route[h.routeIdx];
    return;
  }
  if (randomGoals_.empty()) {
    h.field = -1;
    return;
  }
  const auto n = randomGoals_.size();
  int next = randomGoals_[static_cast<std::size_t>(humanRng_.engine() % n)];
  if (next == h.field && n > 1) {
    next = randomGoals_[(static_cast<std::size_t>(humanRng_.engine() % (n - 1)) + 1 +
                         static_cast<std::size_t>(std::find(randomGoals_.begin(), randomGoals_.end(), next) -
                                                  randomGoals_.begin())) %
                        n];
  }
  h.field = next;
}

void World::pickGoalAwayFromRobots(std::size_t hi) {
  HumanBody& h = humans_[hi];
  std::vector<Vec2> near;
  if (h.route.empty()) {
    const double reach = h.r + maxRadius_ + kBlockingRobotM;
    hash_.forEachNear(h.p, reach, [&](int j) {
      const auto ju = static_cast<std::size_t>(j);
      if (ju < robots_.size() && distance(positions_[ju], h.p) < reach) {
        near.push_back(positions_[ju]);
      }
    });
  }
  if (near.empty() || randomGoals_.empty()) {
    pickGoal(hi);  // nothing to turn from (or a fixed route): as before
    return;
  }
  // A random goal is usually just as blocked: at the mouth of an aisle most of the site lies beyond
  // the robot standing in it, and someone re-drawing every kGiveUpS paces in front of it for minutes
  // while the robot waits for them. Take the first goal, from a random start, whose way leads away.
  const auto n = randomGoals_.size();
  const auto start = static_cast<std::size_t>(humanRng_.engine() % n);
  for (std::size_t k = 0; k < n; ++k) {
    const int g = randomGoals_[(start + k) % n];
    if (g == h.field) {
      continue;
    }
    const Vec2 e = fields_[static_cast<std::size_t>(g)].direction(sc_.map, h.p);
    if (e.squaredNorm() < 1e-12) {
      continue;  // unreachable from here, or already there
    }
    const bool intoRobot = std::any_of(near.begin(), near.end(), [&](Vec2 q) {
      const Vec2 d = q - h.p;
      return e.dot(d) > kIntoRobotCos * len(d);
    });
    if (!intoRobot) {
      h.field = g;
      return;
    }
  }
  // Every way leads into a robot (someone between two robots that face each other, each waiting
  // for them): step out of the gap first. Drawing a goal here sent them to and fro between the two
  // for minutes in a mixed-fleet run.
  if (!stepAside(h, near)) {
    pickGoal(hi);  // hemmed in on every side: wait it out as before
  }
}

bool World::stepAside(HumanBody& h, const std::vector<Vec2>& near) {
  constexpr int kDirections = 16;
  constexpr double kSteps[] = {1.5, 1.0};
  double best = -1.0;
  for (const double step : kSteps) {
    for (int k = 0; k < kDirections; ++k) {
      const double a = 2.0 * kPi * k / kDirections;
      const Vec2 e{std::cos(a), std::sin(a)};
      const Vec2 q = h.p + e * step;
      const bool intoRobot = std::any_of(near.begin(), near.end(), [&](Vec2 r) {
        const Vec2 d = r - h.p;
        return e.dot(d) > kIntoRobotCos * len(d);
      });
      if (intoRobot) {
        continue;
      }
      bool clear = true;
      for (double s = 0.1; s <= step + 1e-9 && clear; s += 0.1) {
        clear = discGridPenetration(sc_.map, h.p + e * s, h.r + 0.05) <= 0.0;
      }
      if (!clear) {
        continue;
      }
      double gap = 1e9;
      for (const Vec2 r : near) {
        gap = std::min(gap, distance(q, r));
      }
      if (gap > best) {
        best = gap;
        h.aside = q;
      }
    }
    if (best >= 0.0) {
      break;  // a full step if one is free
    }
  }
  if (best < 0.0) {
    return false;
  }
  h.asideUntil = time() + kGiveUpS;
  return true;
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

void World::stepHumans() {
  const double dt = sc_.dt;
  const double now = time();
  const SocialForceParams& sf = sc_.social;
  const std::size_t nr = robots_.size();
  // Goals first (sequential: leaders decide, followers copy), then forces from the step-start state.
  for (std::size_t i = 0; i < humans_.size(); ++i) {
    HumanBody& h = humans_[i];
    if (h.leader != static_cast<int>(i)) {
      const HumanBody& l = humans_[static_cast<std::size_t>(h.leader)];
      h.field = l.field;
      h.stopUntil = l.stopUntil;
      h.aside = l.aside;  // out of a gap together (each steering for the leader's point)
      h.asideUntil = l.asideUntil;
      continue;
    }
    // People who cannot get past (a robot waiting in a narrow aisle, a crowd) do not push forever:
    // after kGiveUpS without kProgressM of progress they turn to another goal.
    if (h.progressAt < 0 || now < h.stopUntil || distance(h.p, h.progressRef) > kProgressM) {
      h.progressRef = h.p;
      h.progressAt = now;
    } else if (h.field >= 0 && now - h.progressAt > kGiveUpS) {
      h.progressRef = h.p;
      h.progressAt = now;
      pickGoalAwayFromRobots(i);
      continue;
    }
    if (h.asideUntil >= 0.0 && (now >= h.asideUntil || distance(h.p, h.aside) < kArrive)) {
      h.asideUntil = -1.0;  // out of the gap: on to a new goal
      pickGoal(i);
      continue;
    }
    if (h.field >= 0 && now >= h.stopUntil &&
        distance(h.p, fields_[static_cast<std::size_t>(h.field)].goal()) < kArrive) {
      if (uniform01(humanRng_) < sc_.crowd.stopProbability) {
        h.stopUntil =
            now + sc_.crowd.stopMinS + uniform01(humanRng_) * (sc_.crowd.stopMaxS - sc_.crowd.stopMinS);
      }
      pickGoal(i);
    }
  }
  std::vector<Vec2> newP(humans_.size());
  std::vector<Vec2> newV(humans_.size());
  for (std::size_t i = 0; i < humans_.size(); ++i) {
    const HumanBody& h = humans_[i];
    Vec2 e;
    if (h.asideUntil >= 0.0) {
      e = (h.aside - h.p).normalized();
    } else if (h.field >= 0 && now >= h.stopUntil) {
      e = fields_[static_cast<std::size_t>(h.field)].direction(sc_.map, h.p);
    }
    Vec2 f = drivingForce(e * h.v0, h.v, sf.tau);
    const Vec2 heading = h.v.squaredNorm() > 1e-6 ? h.v.normalized() : e;
    hash_.forEachNear(h.p, sf.cutoff, [&](int j) {
      const auto ju = static_cast<std::size_t>(j);
      if (ju == nr + i) {
        return;
      }
      const Vec2 q = positions_[ju];
      if ((q - h.p).squaredNorm() > sf.cutoff * sf.cutoff) {
        return;
      }
      if (ju < nr) {
        f += bodyRepulsion(sf.robotA, sf.robotB, sf.lambda, h.p, h.r, heading, q, radii_[ju]);
      } else {
        f += bodyRepulsion(sf.humanA, sf.humanB, sf.lambda, h.p, h.r, heading, q, radii_[ju]);
      }
    });
    double wd = 0.0;
    Vec2 away;
    if (nearestBlocked(sc_.map, h.p, h.r + 5.0 * sf.wallB, wd, away)) {
      f += wallRepulsion(sf.wallA, sf.wallB, h.r, wd, away);
    }
    Vec2 v = h.v + f * dt;
    const double vmax = sf.maxSpeedFactor * h.v0;
    if (v.norm() > vmax) {
      v = v.normalized() * vmax;
    }
    newV[i] = v;
    newP[i] = h.p + v * dt;
  }
  for (std::size_t i = 0; i < humans_.size(); ++i) {
    HumanBody& h = humans_[i];
    const double before = discGridPenetration(sc_.map, h.p, h.r);
    // How far inside the keep distance of the nearest robot (step-start poses) a position is. The
    // social force is soft: alone it lets a person press into a robot standing in an aisle,
    // which no one does with a machine in view.
    auto crowding = [&](Vec2 p) {
      double worst = 0.0;
      if (sf.robotKeep < 0.0) {
        return worst;
      }
      hash_.forEachNear(p, h.r + maxRadius_ + sf.robotKeep, [&](int j) {
        const auto ju = static_cast<std::size_t>(j);
        if (ju < nr) {
          worst = std::max(worst, sf.robotKeep - (len(p - positions_[ju]) - h.r - radii_[ju]));
        }
      });
      return worst;
    };
    const double crowdedBefore = crowding(h.p);
    auto ok = [&](Vec2 p) {
      const double a = discGridPenetration(sc_.map, p, h.r);
      const double c = crowding(p);
      return (a <= 0.0 || a <= before) && (c <= 0.0 || c <= crowdedBefore);
    };
    if (ok(newP[i])) {
      h.p = newP[i];
      h.v = newV[i];
    } else if (const Vec2 px{newP[i].x, h.p.y}; ok(px)) {  // slide along the wall
      h.p = px;
      h.v = {newV[i].x, 0.0};
    } else if (const Vec2 py{h.p.x, newP[i].y}; ok(py)) {
      h.p = py;
      h.v = {0.0, newV[i].y};
    } else if (const auto turned = turnedStep(h.p, newV[i], dt, ok)) {
      h.p = turned->first;
      h.v = turned->second;
    } else {
      h.v = {};
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

void World::scanInto(std::size_t ri, std::vector<float>& out) const {
  const SensorSpec& s = sc_.robots[ri].sensors;
  const Pose2 pose = robots_[ri].pose;
  const int n = s.rays;
  out.assign(static_cast<std::size_t>(n), static_cast<float>(s.rangeMax));
  if (n == 0) {
    return;
  }
  const bool full = s.fov >= 2.0 * kPi - 1e-9;
  const double inc = n > 1 ? (full ? s.fov / n : s.fov / (n - 1)) : 0.0;
  const double amin = full ? -kPi : -0.5 * s.fov;
  const geometry::GridView view = sc_.map.view();
  std::vector<double> best(static_cast<std::size_t>(n));
  std::vector<Vec2> dirs(static_cast<std::size_t>(n));
  for (int k = 0; k < n; ++k) {
    const double a = pose.theta + amin + k * inc;
    dirs[static_cast<std::size_t>(k)] = {std::cos(a), std::sin(a)};
  }
  for (int k = 0; k < n; ++k) {
    const auto hit = geometry::raycastGrid(view, pose.position(), pose.theta + amin + k * inc, s.rangeMax);
    best[static_cast<std::size_t>(k)] = hit.hit ? hit.range : s.rangeMax;
  }
  // Other bodies: only the rays inside each disc's angular extent are intersected.
  const Vec2 o = pose.position();
  hash_.forEachNear(o, s.rangeMax + maxRadius_, [&](int j) {
    const auto ju = static_cast<std::size_t>(j);
    if (ju == ri) {
      return;
    }
    const Vec2 d = positions_[ju] - o;
    const double dist = len(d);
    const double rj = radii_[ju];
    if (dist <= rj || dist - rj >= s.rangeMax) {
      return;
    }
    const double half = std::asin(rj / dist);
    const double bearing = wrapAngle(std::atan2(d.y, d.x) - pose.theta);
    const int k0 = static_cast<int>(std::ceil((bearing - half - amin) / inc));
    const int k1 = static_cast<int>(std::floor((bearing + half - amin) / inc));
    for (int kk = k0; kk <= k1; ++kk) {
      int k = kk;
      if (full) {
        k = ((k % n) + n) % n;
      } else if (k < 0 || k >= n) {
        continue;
      }
      const Vec2 u = dirs[static_cast<std::size_t>(k)];
      const double proj = d.dot(u);
      const double perp2 = dist * dist - proj * proj;
      if (proj <= 0.0 || perp2 > rj * rj) {
        continue;
      }
      const double t = proj - std::sqrt(rj * rj - perp2);
      double& b = best[static_cast<std::size_t>(k)];
      b = std::min(b, t);
    }
  });
  for (int k = 0; k < n; ++k) {
    out[static_cast<std::size_t>(k)] = static_cast<float>(best[static_cast<std::size_t>(k)]);
  }
}

std::vector<float> World::scan(std::size_t robot) const {
  std::vector<float> out;
  scanInto(robot, out);
  return out;
}

SensorReading World::sensorFrame(std::size_t i, bool withScan) {
  RobotBody& r = robots_[i];
  const RobotSpec& spec = sc_.robots[i];
  const SensorSpec& s = spec.sensors;
  SensorReading f;
  f.robot = i;
  f.seq = r.frameSeq++;
  f.dsLeft = r.odomLeft;
  f.dsRight = r.odomRight;
  f.wheelLeftTotal = r.odomLeftTotal;
  f.wheelRightTotal = r.odomRightTotal;
  r.odomLeft = r.odomRight = 0.0;
  const bool full = s.fov >= 2.0 * kPi - 1e-9;
  f.angleMin = static_cast<float>(full ? -kPi : -0.5 * s.fov);
  f.angleIncrement = static_cast<float>(s.rays > 1 ? (full ? s.fov / s.rays : s.fov / (s.rays - 1)) : 0.0);
  f.rangeMax = static_cast<float>(s.rangeMax);
  if (withScan) {
    scanInto(i, f.ranges);
    for (auto& x : f.ranges) {
      if (x < f.rangeMax) {
        x = static_cast<float>(
            std::clamp(static_cast<double>(x) + normal(sensorRng_, s.rangeSigma), 0.0, s.rangeMax));
      }
    }
  }
  if (s.compass) {
    f.compassValid = true;
    f.compass = wrapAngle(r.pose.theta + normal(sensorRng_, s.compassSigma));
  }
  if (s.landmarks) {
    const geometry::GridView view = sc_.map.view();
    for (const auto& lm : sc_.landmarks) {
      const Vec2 d = lm.position - r.pose.position();
      const double dist = d.norm();
      if (dist > s.landmarkRange || f.landmarks.size() >= 64) {
        continue;
      }
      const double a = std::atan2(d.y, d.x);
      const auto hit = geometry::raycastGrid(view, r.pose.position(), a, dist);
      // A landmark mounted on a shelf face is visible when the ray stops at its own cell.
      const bool seen = !hit.hit || hit.range >= dist - 1e-6 ||
                        (hit.cx == sc_.map.cellX(lm.position.x) && hit.cy == sc_.map.cellY(lm.position.y));
      if (seen) {
        f.landmarks.emplace_back(
            lm.id, static_cast<float>(wrapAngle(a - r.pose.theta + normal(sensorRng_, s.bearingSigma))));
      }
    }
  }
  if (s.detections) {
    const Vec2 o = r.pose.position();
    std::vector<int> seen;
    hash_.forEachNear(o, s.detectionRange, [&](int j) {
      if (static_cast<std::size_t>(j) != i &&
          len(o - positions_[static_cast<std::size_t>(j)]) <= s.detectionRange) {
        seen.push_back(j);
      }
    });
    std::sort(seen.begin(), seen.end());
    const double c = std::cos(r.pose.theta);
    const double sn = std::sin(r.pose.theta);
    for (int j : seen) {
      if (f.detections.size() >= 256) {
        break;
      }
      const auto ju = static_cast<std::size_t>(j);
      const Vec2 d = positions_[ju] - o;
      const Vec2 local{c * d.x + sn * d.y, -sn * d.x + c * d.y};  // into the robot frame
      f.detections.push_back(
          {ju >= robots_.size(), static_cast<float>(local.x + normal(sensorRng_, s.rangeSigma)),
           static_cast<float>(local.y + normal(sensorRng_, s.rangeSigma)), static_cast<float>(radii_[ju])});
    }
  }
  f.battery = static_cast<float>(r.battery);
  f.charging = r.charging;
  return f;
}

std::vector<SensorReading> World::sensorFrames(bool withScan) {
  std::vector<SensorReading> out;
  for (std::size_t i = 0; i < robots_.size(); ++i) {
    if (step_ % sensorEvery_[i] == 0) {
      out.push_back(sensorFrame(i, withScan));
    }
  }
  return out;
}

std::vector<PredictedDisc> World::predictHuman(std::size_t i) const {
  const HumanBody& h = humans_[i];
  std::vector<PredictedDisc> out;
  const int n =
      std::min(64, static_cast<int>(std::floor(sc_.predictionHorizonS / sc_.predictionDt + 1e-9)) + 1);
  for (int k = 0; k < n; ++k) {
    const double t = k * sc_.predictionDt;
    const Vec2 p = h.p + h.v * t;
    out.push_back({p.x, p.y, h.r, sc_.predictionSigma0 + sc_.predictionSigmaRate * t});
  }
  return out;
}

}  // namespace fleet::sim
