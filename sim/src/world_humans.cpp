#include "fleet/sim/world.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "fleet/core/angles.hpp"
#include "fleet/sim/social_force.hpp"
#include "world_math.hpp"

namespace fleet::sim {

using world_detail::len;
using world_detail::normal;
using world_detail::uniform01;

namespace {

constexpr double kArrive = 0.6;          // m: a human reached its goal
constexpr double kProgressM = 0.5;       // m: moving less than this in kGiveUpS is being stuck
constexpr double kGiveUpS = 5.0;         // s of being stuck before choosing another goal
constexpr double kBlockingRobotM = 1.0;  // m (surface gap): a robot this close can be what blocks someone
constexpr double kIntoRobotCos = 0.5;    // a way within 60° of a robot's bearing leads into it

/// The way `e` (a unit vector) from `p` leads into the robot at `q`: within 60° of its bearing, or,
/// near it, within the angle that its disc and the person's (`clear`: both radii and the keep
/// distance) cover from there. A person 0.6 m from a robot standing 0.54 m below a shelf face
/// counted the way past it, 69° off its bearing, as free and stood there for minutes (dense fleet
/// check, seed 8): at that distance the robot covers ±90°.
bool leadsInto(Vec2 p, Vec2 e, Vec2 q, double clear) {
  const Vec2 d = q - p;
  const double dist = len(d);
  const double covered = clear >= dist ? 0.0 : std::sqrt(1.0 - (clear / dist) * (clear / dist));
  return e.dot(d) > std::min(kIntoRobotCos, covered) * dist;
}

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
  const double keepOff = h.r + maxRadius_ + std::max(0.0, sc_.social.robotKeep);
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
    const bool intoRobot =
        std::any_of(near.begin(), near.end(), [&](Vec2 q) { return leadsInto(h.p, e, q, keepOff); });
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
  const double keepOff = h.r + maxRadius_ + std::max(0.0, sc_.social.robotKeep);
  constexpr double kSteps[] = {1.5, 1.0};
  double best = -1.0;
  for (const double step : kSteps) {
    for (int k = 0; k < kDirections; ++k) {
      const double a = 2.0 * kPi * k / kDirections;
      const Vec2 e{std::cos(a), std::sin(a)};
      const Vec2 q = h.p + e * step;
      const bool intoRobot =
          std::any_of(near.begin(), near.end(), [&](Vec2 r) { return leadsInto(h.p, e, r, keepOff); });
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
