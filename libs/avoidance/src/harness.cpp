#include "fleet/avoidance/harness.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <random>

#include "fleet/avoidance/clearance.hpp"
#include "fleet/control/diff_drive_kinematics.hpp"
#include "fleet/core/angles.hpp"
#include "fleet/planning/astar.hpp"

namespace fleet::avoidance {

namespace {

// The surface the sensor would see: midpoint and corners of every occupied-cell face that borders
// free space (cell centres would hide the outer half cell from the planners).
std::vector<Vec2> boundaryPoints(const planning::OccupancyGrid& g) {
  std::vector<Vec2> out;
  const double h = g.resolution() * 0.5;
  for (int y = 0; y < g.height(); ++y) {
    for (int x = 0; x < g.width(); ++x) {
      if (!g.blocked({x, y}))
        continue;
      const Vec2 c = g.cellCenter({x, y});
      const int dx[4] = {1, -1, 0, 0};
      const int dy[4] = {0, 0, 1, -1};
      for (int k = 0; k < 4; ++k) {
        const planning::Cell nb{x + dx[k], y + dy[k]};
        if (!g.inside(nb) || g.blocked(nb))
          continue;
        const Vec2 n{static_cast<double>(dx[k]), static_cast<double>(dy[k])};
        const Vec2 mid = c + n * h;
        out.push_back(mid);
        out.push_back(mid + n.perp() * h);
        out.push_back(mid - n.perp() * h);
      }
    }
  }
  return out;
}

struct HumanState {
  Vec2 pos;
  Vec2 vel;
  bool towards_b = true;
};

}  // namespace

Expected<ScenarioResult> runScenario(const Scenario& sc, std::string_view planner_name, bool withSafety,
                                     SafetyParams safety) {
  if (auto v = sc.limits.validate(); !v)
    return fleet::unexpected(v.error());
  const std::size_t n = sc.robots.size();
  std::vector<std::unique_ptr<LocalPlanner>> planners;
  for (std::size_t i = 0; i < n; ++i) {
    auto p = makePlanner(planner_name);
    if (!p)
      return fleet::unexpected(p.error());
    if (withSafety) {
      planners.push_back(std::make_unique<SafePlanner>(std::move(*p), safety));
    } else {
      planners.push_back(std::move(*p));
    }
  }
  const std::vector<Vec2> statics = boundaryPoints(sc.grid);
  const double half_cell = sc.grid.resolution() * 0.5;
  std::vector<Vec2> cells;  // centres of the occupied cells that border free space (contact check)
  for (int y = 0; y < sc.grid.height(); ++y) {
    for (int x = 0; x < sc.grid.width(); ++x) {
      if (sc.grid.blocked({x, y}))
        cells.push_back(sc.grid.cellCenter({x, y}));
    }
  }

  // Global paths (when asked): the remaining path is handed to the planner each cycle, from the
  // path point nearest the robot on.
  std::vector<std::vector<Vec2>> routes(n);
  for (std::size_t i = 0; i < n; ++i) {
    const Vec2 g = sc.robots[i].goal;
    if (sc.globalPath) {
      const auto inflated = sc.grid.inflated(sc.robots[i].radius + sc.pathMargin);
      planning::AStarPlanner astar;
      auto planned = astar.plan(inflated, sc.robots[i].start, {g.x, g.y, 0.0});
      if (!planned)
        return fleet::unexpected(planned.error().code, "robot " + std::to_string(i) +
                                                           ": no global path: " + planned.error().message);
      for (const Pose2& q : planned->poses)
        routes[i].push_back(q.position());
    } else {
      routes[i].push_back(g);
    }
  }
  std::vector<std::size_t> route_from(n, 0);

  std::vector<Pose2> pose(n);
  std::vector<Twist> twist(n);
  std::vector<bool> done(n, false);
  std::vector<double> arrive(n, 0.0), length(n, 0.0);
  for (std::size_t i = 0; i < n; ++i)
    pose[i] = sc.robots[i].start;
  std::mt19937 rng(sc.seed);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  std::vector<HumanState> humans;
  for (const auto& h : sc.humans) {
    HumanState s;
    s.pos = h.randomWalk ? h.a + (h.b - h.a) * 0.5 : h.a;
    s.vel = h.randomWalk ? Vec2{h.speed, 0.0} : (h.b - h.a).normalized() * h.speed;
    humans.push_back(s);
  }

  ScenarioResult res;
  res.planner = std::string(planner_name);
  res.scenario = sc.name;
  res.robots = static_cast<int>(n);
  res.minSeparation = std::numeric_limits<double>::infinity();
  std::vector<double> compute_us;
  std::vector<std::uint8_t> in_contact(n * (n + 1 + sc.humans.size()), 0);
  std::vector<Vec2> scan;
  std::vector<MovingDisc> discs;
  std::vector<Twist> cmds(n);
  const double range2 = sc.sensingRange * sc.sensingRange;

  int step = 0;
  for (; step < sc.maxSteps; ++step) {
    if (std::all_of(done.begin(), done.end(), [](bool d) { return d; }))
      break;
    // Plan all robots on the same snapshot, then move them together.
    for (std::size_t i = 0; i < n; ++i) {
      cmds[i] = {};
      if (done[i])
        continue;
      const Vec2 p = pose[i].position();
      scan.clear();
      for (const Vec2& q : statics) {
        if ((q - p).squaredNorm() <= range2)
          scan.push_back(q);
      }
      discs.clear();
      for (std::size_t j = 0; j < n; ++j) {
        if (j == i || (pose[j].position() - p).squaredNorm() > range2)
          continue;
        discs.push_back({pose[j].position(), pose[j].heading() * twist[j].v, sc.robots[j].radius});
      }
      for (std::size_t h = 0; h < humans.size(); ++h) {
        if ((humans[h].pos - p).squaredNorm() > range2)
          continue;
        discs.push_back({humans[h].pos, humans[h].vel, sc.humans[h].radius});
      }
      const auto& route = routes[i];
      for (std::size_t k = route_from[i]; k < route.size() && k < route_from[i] + 20; ++k) {
        if ((route[k] - p).squaredNorm() < (route[route_from[i]] - p).squaredNorm())
          route_from[i] = k;
      }
      LocalView view;
      view.robot = {pose[i], twist[i], sc.robots[i].radius};
      view.path = std::span<const Vec2>(route).subspan(route_from[i]);
      view.scan = scan;
      view.discs = discs;
      view.limits = sc.limits;
      view.dt = sc.dt;
      view.goalTolerance = sc.goalTolerance;
      const auto t0 = std::chrono::steady_clock::now();
      const Command c = planners[i]->plan(view);
      const auto t1 = std::chrono::steady_clock::now();
      compute_us.push_back(std::chrono::duration<double, std::micro>(t1 - t0).count());
      if (c.overruled)
        ++res.overruled;
      if (c.status == PlanStatus::kGoalReached) {
        done[i] = true;
        twist[i] = {};
        arrive[i] = static_cast<double>(step) * sc.dt;
        continue;
      }
      cmds[i] = c.twist;
    }
    for (std::size_t i = 0; i < n; ++i) {
      if (done[i])
        continue;
      const auto lt = control::applyLimits(sc.limits, cmds[i], twist[i], sc.dt);
      const Pose2 next = control::DiffDriveKinematics::integrateExact(pose[i], lt.twist, sc.dt);
      length[i] += fastDistance(next.position(), pose[i].position());
      pose[i] = next;
      twist[i] = lt.twist;
    }
    for (std::size_t h = 0; h < humans.size(); ++h) {
      auto& s = humans[h];
      const auto& spec = sc.humans[h];
      if (spec.randomWalk) {
        if (uni(rng) < 0.05) {
          const double a = 2.0 * kPi * uni(rng);
          s.vel = Vec2{std::cos(a), std::sin(a)} * spec.speed;
        }
        Vec2 nxt = s.pos + s.vel * sc.dt;
        const Vec2 lo{std::min(spec.a.x, spec.b.x), std::min(spec.a.y, spec.b.y)};
        const Vec2 hi{std::max(spec.a.x, spec.b.x), std::max(spec.a.y, spec.b.y)};
        if (nxt.x < lo.x || nxt.x > hi.x)
          s.vel.x = -s.vel.x;
        if (nxt.y < lo.y || nxt.y > hi.y)
          s.vel.y = -s.vel.y;
        s.pos = s.pos + s.vel * sc.dt;
      } else {
        const Vec2 target = s.towards_b ? spec.b : spec.a;
        if (fastDistance(s.pos, target) <= spec.speed * sc.dt) {
          s.pos = target;
          s.towards_b = !s.towards_b;
          s.vel = ((s.towards_b ? spec.b : spec.a) - s.pos).normalized() * spec.speed;
        } else {
          s.pos = s.pos + s.vel * sc.dt;
        }
      }
    }
    // Contacts and separation.
    const std::size_t stride = n + 1 + humans.size();
    for (std::size_t i = 0; i < n; ++i) {
      const Vec2 p = pose[i].position();
      const double ri = sc.robots[i].radius;
      auto note = [&](std::size_t slot, double gap) {
        res.minSeparation = std::min(res.minSeparation, gap);
        const bool touch = gap < -1e-9;
        auto& flag = in_contact[i * stride + slot];
        if (touch && flag == 0) {
          ++res.collisions;
          if (slot < n) {
            ++res.robotCollisions;
          } else if (slot == n) {
            ++res.staticCollisions;
          } else {
            ++res.humanCollisions;
            if (std::abs(twist[i].v) > 1e-3)
              ++res.humanHitsWhileMoving;
            const Vec2 to_h = humans[slot - n - 1].pos - p;
            if (pose[i].heading().dot(to_h) * twist[i].v > 0.05 * std::sqrt(to_h.squaredNorm()))
              ++res.humanHitsByRobot;
          }
        }
        flag = touch ? 1 : 0;
      };
      for (std::size_t j = i + 1; j < n; ++j) {
        note(j, fastDistance(p, pose[j].position()) - ri - sc.robots[j].radius);
      }
      // Exact distance to the occupied cells (squares), not to their centres.
      double wall = std::numeric_limits<double>::infinity();
      for (const Vec2& q : cells) {
        const double dx = std::max(0.0, std::abs(p.x - q.x) - half_cell);
        const double dy = std::max(0.0, std::abs(p.y - q.y) - half_cell);
        wall = std::min(wall, dx * dx + dy * dy);
      }
      if (!statics.empty())
        note(n, std::sqrt(wall) - ri);
      for (std::size_t h = 0; h < humans.size(); ++h) {
        note(n + 1 + h, fastDistance(p, humans[h].pos) - ri - sc.humans[h].radius);
      }
    }
  }
  double t_sum = 0.0;
  double l_sum = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    if (!done[i])
      continue;
    ++res.reached;
    t_sum += arrive[i];
    l_sum += length[i];
    res.makespan = std::max(res.makespan, arrive[i]);
  }
  if (res.reached < res.robots)
    res.makespan = static_cast<double>(step) * sc.dt;
  if (res.reached > 0) {
    res.meanTimeToGoal = t_sum / res.reached;
    res.meanPathLength = l_sum / res.reached;
  }
  for (std::size_t i = 0; i < n; ++i) {
    res.meanRemaining += fastDistance(pose[i].position(), sc.robots[i].goal) / static_cast<double>(n);
    res.meanTravelled += length[i] / static_cast<double>(n);
  }
  res.agentSteps = static_cast<std::int64_t>(compute_us.size());
  if (!compute_us.empty()) {
    double s = 0.0;
    for (const double c : compute_us)
      s += c;
    res.computeMeanUs = s / static_cast<double>(compute_us.size());
    const std::size_t k = std::min(compute_us.size() - 1,
                                   static_cast<std::size_t>(0.99 * static_cast<double>(compute_us.size())));
    std::nth_element(compute_us.begin(), compute_us.begin() + static_cast<std::ptrdiff_t>(k),
                     compute_us.end());
    res.computeP99Us = compute_us[k];
  }
  return res;
}

Scenario circleSwap(int n, double circle_radius, double robot_radius) {
  Scenario sc;
  sc.name = "circle_swap_" + std::to_string(n);
  sc.grid = planning::OccupancyGrid(1, 1, 0.1, {-1000.0, -1000.0});  // empty: no static obstacles
  for (int i = 0; i < n; ++i) {
    const double a = 2.0 * kPi * static_cast<double>(i) / static_cast<double>(n);
    const Vec2 p{circle_radius * std::cos(a), circle_radius * std::sin(a)};
    sc.robots.push_back({{p.x, p.y, wrapAngle(a + kPi)}, -p, robot_radius});
  }
  sc.maxSteps = static_cast<int>(40.0 * circle_radius / (sc.limits.vMax * sc.dt)) + 2000;
  return sc;
}

Scenario aisleCrossing(int robots_each_way, int crossing_humans, std::uint32_t seed) {
  Scenario sc;
  sc.name = "aisle_crossing";
  sc.seed = seed;
  // 24 m × 10 m at 0.1 m: shelves y ∈ [−3, −1.5] and [1.5, 3] over x ∈ [1, 23], cross aisle x ∈ [11, 13].
  sc.grid = planning::OccupancyGrid(240, 100, 0.1, {0.0, -5.0});
  for (int y = 0; y < 100; ++y) {
    for (int x = 0; x < 240; ++x) {
      const Vec2 c = sc.grid.cellCenter({x, y});
      const bool shelf = std::abs(c.y) >= 1.5 && std::abs(c.y) <= 3.0 && c.x >= 1.0 && c.x <= 23.0 &&
                         !(c.x >= 11.0 && c.x <= 13.0);
      if (shelf)
        sc.grid.setBlocked({x, y});
    }
  }
  for (int k = 0; k < robots_each_way; ++k) {
    const double lane = -0.6 + 1.2 * static_cast<double>(k) / std::max(1, robots_each_way - 1);
    sc.robots.push_back({{0.5 + 1.2 * k, lane, 0.0}, {23.0, lane}, 0.35});
    sc.robots.push_back({{23.5 - 1.2 * k, -lane, kPi}, {1.0, -lane}, 0.35});
  }
  for (int h = 0; h < crossing_humans; ++h) {
    const double x = 11.5 + static_cast<double>(h);
    sc.humans.push_back({{x, -4.5 + 0.8 * h}, {x, 4.5}, 1.0, 0.3, false});
  }
  sc.humans.push_back({{3.0, -1.2}, {21.0, 1.2}, 0.8, 0.3, true});
  sc.maxSteps = 2500;
  return sc;
}

Scenario obstacleCourse() {
  Scenario sc;
  sc.name = "obstacle_course";
  // 18 m × 12 m at 0.1 m with a wall around it; boxes (centre x, centre y, half width, half
  // height) leave 3.6 m to the walls, more than Table 2.3's dSafe of 1 m on each side.
  sc.grid = planning::OccupancyGrid(180, 120, 0.1, {0.0, -6.0});
  struct Box {
    double cx, cy, hx, hy;
  };
  const Box boxes[] = {{5.0, 0.0, 0.5, 1.0}, {9.5, 1.2, 0.6, 1.2}, {13.5, -1.2, 0.6, 1.2}};
  for (int y = 0; y < 120; ++y) {
    for (int x = 0; x < 180; ++x) {
      const Vec2 c = sc.grid.cellCenter({x, y});
      bool occ = x == 0 || y == 0 || x == 179 || y == 119;
      for (const Box& b : boxes) {
        occ = occ || (std::abs(c.x - b.cx) <= b.hx && std::abs(c.y - b.cy) <= b.hy);
      }
      if (occ)
        sc.grid.setBlocked({x, y});
    }
  }
  // The goal lies 0.9 m in front of the end wall, as stations do: inside Elastic Strips' dSafe.
  sc.robots.push_back({{1.0, 0.0, 0.0}, {17.0, 0.0}, 0.35});
  sc.maxSteps = 4000;  // Bug1 tours every box it meets once and a half at 0.3 m/s: ~70 m
  sc.globalPath = true;
  return sc;
}

Scenario aisleCrossingAlone(int crossing_humans, std::uint32_t seed) {
  Scenario sc = aisleCrossing(1, crossing_humans, seed);
  sc.name = "aisle_crossing_alone";
  sc.robots.resize(1);
  sc.robots[0].start = {0.5, 0.0, 0.0};
  sc.robots[0].goal = {23.0, 0.0};
  sc.globalPath = true;
  return sc;
}

}  // namespace fleet::avoidance
