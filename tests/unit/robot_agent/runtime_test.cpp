// The robot agent's runtime pieces: the decoded risk map, the route planner (A* with risk as a
// cost layer, the fallback chain) and the worker pool that steps many agents per cycle.

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <functional>
#include <memory>
#include <random>

#include "agent.hpp"
#include "fleet/planning/astar.hpp"
#include "fleet/risk/rle.hpp"
#include "fleet/service/risk_lookup_of.hpp"
#include "route_planner.hpp"
#include "worker_pool.hpp"

using namespace fleet;

namespace {

msg::RiskMap riskMap(int w, int h, double res, Vec2 origin, int k, const std::vector<std::uint8_t>& levels) {
  msg::RiskMap m;
  m.origin_x = origin.x;
  m.origin_y = origin.y;
  m.resolution = res;
  m.width = static_cast<std::uint32_t>(w);
  m.height = static_cast<std::uint32_t>(h);
  m.levels = static_cast<std::uint8_t>(k);
  for (const auto& r : risk::encodeRle(levels)) {
    m.runs.push_back({r.level, r.length});
  }
  return m;
}

// Risk as the route planner weighs it: entering a cell costs its step x (1 + w p).
Expected<planning::GridPath> riskAstar(const planning::OccupancyGrid& g, planning::Cell s, planning::Cell t,
                                       const std::function<double(Vec2)>& risk, double w) {
  planning::CostLayers layers;
  layers.push_back(std::make_shared<planning::EnterCellCost>("risk", [&](planning::Cell c) {
    return 1.0 + w * (risk ? std::clamp(risk(g.cellCenter(c)), 0.0, 1.0) : 0.0);
  }));
  return planning::astar(g, s, t, layers);
}

agent::RouteOptions routeOptions(std::string kind, std::shared_ptr<const planning::LaneMap> lanes,
                                 double riskWeight) {
  agent::RouteOptions o;
  o.planner = std::move(kind);
  o.lanes = std::move(lanes);
  o.riskWeight = riskWeight;
  return o;
}

}  // namespace

TEST(RiskLookup, LooksUpTheLevelUpperBoundOfTheCellAndZeroOffTheMap) {
  std::vector<std::uint8_t> levels(4 * 3, 0);
  levels[1 * 4 + 2] = 5;  // cell (2, 1)
  levels[0] = 10;
  const auto f = service::riskLookupOf(riskMap(4, 3, 0.5, {-1.0, 2.0}, 10, levels));
  ASSERT_TRUE(f) << f.error().message;
  EXPECT_DOUBLE_EQ((*f)->at({-1.0 + 1.25, 2.0 + 0.75}), 0.5);
  EXPECT_DOUBLE_EQ((*f)->at({-0.99, 2.01}), 1.0);
  EXPECT_DOUBLE_EQ((*f)->at({-1.0 + 1.25, 2.0 + 0.25}), 0.0);
  EXPECT_DOUBLE_EQ((*f)->at({-1.01, 2.1}), 0.0) << "left of the map";
  EXPECT_DOUBLE_EQ((*f)->at({0.0, 3.51}), 0.0) << "above the map";
}

TEST(RiskLookup, RejectsWhatARemoteWriterCouldGetWrong) {
  std::vector<std::uint8_t> levels(12, 1);
  auto m = riskMap(4, 3, 0.5, {}, 4, levels);
  m.runs.back().count += 1;
  EXPECT_FALSE(service::riskLookupOf(m));
  m = riskMap(4, 3, 0.5, {}, 4, levels);
  m.runs.front().level = 9;
  EXPECT_FALSE(service::riskLookupOf(m));
  m = riskMap(4, 3, 0.0, {}, 4, levels);
  EXPECT_FALSE(service::riskLookupOf(m));
  m = riskMap(4, 3, 0.5, {}, 4, levels);
  m.levels = 0;
  EXPECT_FALSE(service::riskLookupOf(m));
}

TEST(RiskAstar, WithoutRiskItCostsWhatPlainAstarCosts) {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 30; ++trial) {
    planning::OccupancyGrid g(30, 25, 0.1);
    std::bernoulli_distribution wall(0.25);
    for (int y = 0; y < 25; ++y) {
      for (int x = 0; x < 30; ++x) {
        if (wall(rng)) {
          g.setBlocked({x, y});
        }
      }
    }
    g.setBlocked({0, 0}, false);
    g.setBlocked({29, 24}, false);
    const auto plain = planning::astar(g, {0, 0}, {29, 24});
    const auto risky = riskAstar(g, {0, 0}, {29, 24}, {}, 1.0);
    ASSERT_EQ(plain.has_value(), risky.has_value()) << "trial " << trial;
    if (plain) {
      EXPECT_NEAR(plain->cost, risky->cost, 1e-9) << "trial " << trial;
    }
  }
}

TEST(RiskAstar, GoesAroundRiskWithinTheDetourBound) {
  // An open 40×21 room; a risky band across the middle of the straight line, with a gap at the top.
  planning::OccupancyGrid g(40, 21, 1.0);
  auto risk = [](Vec2 p) { return (p.x > 15 && p.x < 25 && p.y < 15) ? 1.0 : 0.0; };
  const planning::Cell s{2, 5};
  const planning::Cell t{37, 5};
  const auto shortest = planning::astar(g, s, t);
  ASSERT_TRUE(shortest);
  for (const double w : {0.25, 1.0, 3.0}) {
    const auto r = riskAstar(g, s, t, risk, w);
    ASSERT_TRUE(r);
    double length = 0.0;
    double riskyLength = 0.0;
    for (std::size_t i = 1; i < r->cells.size(); ++i) {
      const double step = std::hypot(r->cells[i].x - r->cells[i - 1].x, r->cells[i].y - r->cells[i - 1].y);
      length += step;
      riskyLength += step * risk(g.cellCenter(r->cells[i]));
    }
    EXPECT_NEAR(r->cost, length + w * riskyLength, 1e-9);
    EXPECT_LE(length, (1.0 + w) * shortest->cost + 1e-9) << "detour bound, w = " << w;
    EXPECT_LE(r->cost, shortest->cost * (1.0 + w) + 1e-9);
    if (w >= 3.0) {
      EXPECT_EQ(riskyLength, 0.0) << "a heavy weight takes the gap";
    }
    if (w <= 0.25) {
      EXPECT_GT(riskyLength, 0.0) << "a light weight does not detour 20 cells for 10 risky ones";
    }
  }
}

TEST(RoutePlanner, IsBuiltOnceByNameAndRefusesUnknownPlanners) {
  auto grid = std::make_shared<const planning::OccupancyGrid>(20, 10, 0.5);
  for (const char* kind : {"astar", "wavefront"}) {
    const auto p = agent::makeGlobalPlanner(kind, {});
    ASSERT_TRUE(p) << kind;
    EXPECT_STREQ((*p)->name(), kind);
  }
  EXPECT_TRUE(agent::makeGlobalPlanner("ompl", {}));
  const auto bad = agent::makeGlobalPlanner("dijkstra", {});
  ASSERT_FALSE(bad);
  EXPECT_EQ(bad.error().code, "unknown_planner");
  EXPECT_NE(bad.error().message.find("'dijkstra'"), std::string::npos);
  EXPECT_THROW(agent::RoutePlanner(routeOptions("rrt", nullptr, 1.0), grid, grid), std::invalid_argument);
  auto lanes = std::make_shared<const planning::LaneMap>(
      planning::LaneMap::derive(planning::OccupancyGrid(5, 5, 0.5)));
  EXPECT_THROW(agent::RoutePlanner(routeOptions("astar", lanes, 1.0), grid, grid), std::invalid_argument)
      << "a lane map of another size";
  // Lanes are a rule of every path: they make the planner the layered A* whatever was asked.
  auto fits = std::make_shared<const planning::LaneMap>(planning::LaneMap::derive(*grid));
  EXPECT_STREQ(agent::RoutePlanner(routeOptions("wavefront", fits, 1.0), grid, grid).plannerName(), "astar");
}

TEST(RoutePlanner, WeighsRiskInTheFirstTryOnly) {
  // A 40 x 21 room at 1 m with a risky band across the straight line (gap at the top).
  auto grid = std::make_shared<const planning::OccupancyGrid>(40, 21, 1.0);
  std::vector<std::uint8_t> levels(40 * 21, 0);
  for (int y = 0; y < 15; ++y) {
    for (int x = 16; x < 25; ++x) {
      levels[static_cast<std::size_t>(y * 40 + x)] = 4;
    }
  }
  const auto risk = service::riskLookupOf(riskMap(40, 21, 1.0, {}, 4, levels));
  ASSERT_TRUE(risk);
  agent::RoutePlanner route(routeOptions("astar", nullptr, 3.0), grid, grid);
  const Pose2 from{2.5, 5.5, 0.0};
  const Pose2 to{37.5, 5.5, 0.0};
  auto crossesBand = [&](const planning::Path& p) {
    for (std::size_t i = 1; i < p.poses.size(); ++i) {
      for (double t = 0.0; t <= 1.0; t += 0.01) {
        const Vec2 q = p.poses[i - 1].position() + (p.poses[i].position() - p.poses[i - 1].position()) * t;
        if ((*risk)->at(q) > 0.0) {
          return true;
        }
      }
    }
    return false;
  };
  const auto straight = route.route(*grid, from, to);
  ASSERT_TRUE(straight);
  EXPECT_TRUE(crossesBand(*straight)) << "no risk map yet: the shortest path";
  route.setRisk(*risk);
  const auto around = route.route(*grid, from, to);
  ASSERT_TRUE(around);
  EXPECT_FALSE(crossesBand(*around)) << "w = 3 takes the gap";
  // Boxed in (the first grid has a wall across the room): the fallback plans on the planning grid
  // itself, where the wall is not, and no longer weighs risk (a way out, not a preference).
  planning::OccupancyGrid walled = *grid;
  for (int y = 0; y < 21; ++y) {
    walled.setBlocked({30, y});
  }
  const auto fallback = route.route(walled, from, to);
  ASSERT_TRUE(fallback);
  EXPECT_TRUE(crossesBand(*fallback));
  // A detour has no fallback: no way round is an error, and the caller keeps its path.
  EXPECT_FALSE(route.detour(walled, from, to));
  route.setRisk(nullptr);
  EXPECT_TRUE(crossesBand(*route.route(*grid, from, to)));
}

TEST(RoutePlanner, TheSiteRulesApplyToEveryTry) {
  // Two corridors (y < 2.5 and y > 2.5 m) joined at both ends; a rule prices moving left in the
  // lower one x1000 (a one-way zone). From its right end to its left end the route takes the upper
  // corridor, in the first try and in the fallback alike, and the planner asked for (wavefront)
  // becomes the layered A*.
  struct EastboundBelow final : planning::CostLayer {
    double factor(planning::Cell from, planning::Cell to) const override {
      return to.x < from.x && to.y < 5 ? 1000.0 : 1.0;
    }
    const char* name() const override { return "eastbound_below"; }
  };
  planning::OccupancyGrid map(20, 10, 0.5);
  for (int x = 2; x < 18; ++x) {
    map.setBlocked({x, 5});
  }
  auto grid = std::make_shared<const planning::OccupancyGrid>(map);
  auto opt = routeOptions("wavefront", nullptr, 1.0);
  opt.rules.push_back(std::make_shared<EastboundBelow>());
  agent::RoutePlanner route(opt, grid, grid);
  EXPECT_STREQ(route.plannerName(), "astar");
  auto usesUpper = [](const planning::Path& p) {
    return std::any_of(p.poses.begin(), p.poses.end(), [](const Pose2& q) { return q.y > 2.75; });
  };
  const Pose2 from{8.25, 1.25, kPi};
  const Pose2 to{2.25, 1.25, kPi};
  const auto first = route.route(*grid, from, to);
  ASSERT_TRUE(first);
  EXPECT_TRUE(usesUpper(*first));
  planning::OccupancyGrid goalBlocked = map;  // the first try fails: the fallback plans
  goalBlocked.setBlocked(*map.cellAt(to.position()));
  const auto fallback = route.route(goalBlocked, from, to);
  ASSERT_TRUE(fallback);
  EXPECT_TRUE(usesUpper(*fallback));
  agent::RoutePlanner plain(routeOptions("astar", nullptr, 1.0), grid, grid);
  EXPECT_FALSE(usesUpper(*plain.route(*grid, from, to))) << "without the rule: straight along the lower one";
}

TEST(RoutePlanner, OpensAGoalInThePlanningMarginWhenTheBodyFits) {
  // A parking place 0.45 m from a wall: its cell is blocked on the grid inflated by 0.5 m, but a
  // 0.3 m robot fits on it.
  planning::OccupancyGrid raw(40, 20, 0.1);
  for (int x = 0; x < 40; ++x) {
    raw.setBlocked({x, 0});
  }
  auto rawPtr = std::make_shared<const planning::OccupancyGrid>(raw);
  auto grid = std::make_shared<const planning::OccupancyGrid>(raw.inflated(0.5));
  const Vec2 place{2.05, 0.55};
  ASSERT_TRUE(grid->blocked(*grid->cellAt(place)));
  ASSERT_TRUE(agent::bodyFits(raw, place, 0.3));
  EXPECT_FALSE(agent::bodyFits(raw, {2.05, 0.25}, 0.3));
  planning::OccupancyGrid g = *grid;
  agent::openGoal(g, raw, place, 0.3);
  EXPECT_FALSE(g.blocked(*g.cellAt(place)));
  agent::RoutePlanner route(routeOptions("astar", nullptr, 1.0), grid, rawPtr);
  const auto p = route.route(*grid, Pose2{2.05, 1.5, 0.0}, Pose2{place.x, place.y, 0.0});
  ASSERT_TRUE(p) << p.error().message;
  for (const auto& q : p->poses) {
    EXPECT_GE(q.y, 0.5) << "the path keeps its margin up to the goal";
  }
}

TEST(WorkerPool, RunsEveryIndexExactlyOncePerCall) {
  for (const unsigned threads : {1u, 2u, 4u}) {
    agent::WorkerPool pool(threads);
    EXPECT_EQ(pool.threads(), threads);
    for (int call = 0; call < 300; ++call) {
      const std::size_t n = static_cast<std::size_t>(call % 37);
      std::vector<std::atomic<int>> hits(n);
      pool.forEach(n, [&](std::size_t i) { hits[i].fetch_add(1); });
      for (std::size_t i = 0; i < n; ++i) {
        ASSERT_EQ(hits[i].load(), 1) << threads << " threads, call " << call << ", index " << i;
      }
    }
  }
}

TEST(WorkerPool, AgentsSteppedInParallelComputeWhatSequentialSteppingComputes) {
  auto grid = std::make_shared<const planning::OccupancyGrid>(60, 60, 0.25, Vec2{0, 0});
  auto run = [&](unsigned threads) {
    std::vector<std::unique_ptr<agent::Agent>> agents;
    for (int i = 0; i < 12; ++i) {
      agent::AgentParams p;
      p.id = "r" + std::to_string(i);
      p.start = {1.0 + i, 1.0, 0.5};
      p.localPlanner = i % 2 == 0 ? "dwa" : "follow";
      agents.push_back(std::make_unique<agent::Agent>(p, grid, grid));
      msg::TaskAssignment a;
      a.robot_id = p.id;
      a.task_id = "t" + std::to_string(i);
      a.revision = 1;
      a.goals.push_back({{2.0 + i, 12.0, 0.0}, "P", msg::GoalAction::Load, 0.5});
      agents.back()->onAssignment(a);
    }
    agent::WorkerPool pool(threads);
    std::vector<agent::AgentOutput> outs(agents.size());
    std::vector<msg::VelocityCommand> log;
    for (int k = 0; k < 60; ++k) {
      for (std::size_t i = 0; i < agents.size(); ++i) {
        msg::SensorFrame f;
        f.robot_id = agents[i]->id();
        f.ds_left = outs[i].command.v * 0.1 - outs[i].command.w * 0.1;
        f.ds_right = outs[i].command.v * 0.1 + outs[i].command.w * 0.1;
        f.range_max = 8.0f;
        agents[i]->onFrame(f);
      }
      pool.forEach(agents.size(), [&](std::size_t i) { outs[i] = agents[i]->step(k * 100'000'000LL, 0.1); });
      for (const auto& o : outs) {
        log.push_back(o.command);
      }
    }
    return log;
  };
  const auto one = run(1);
  EXPECT_EQ(one, run(3));
  bool moved = false;
  for (const auto& c : one) {
    moved = moved || c.v > 0.1;
  }
  EXPECT_TRUE(moved);
}
