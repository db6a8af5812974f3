// The robot agent's runtime pieces: the decoded risk map, A* with risk as a cost layer, and the
// worker pool that steps many agents per cycle.

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <functional>
#include <memory>
#include <random>

#include "agent.hpp"
#include "fleet/planning/astar.hpp"
#include "fleet/risk/risk_lookup_of.hpp"
#include "fleet/risk/rle.hpp"
#include "straight_releases.hpp"
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

// Risk as a cost layer of A*: entering a cell costs its step x (1 + w p).
Expected<planning::GridPath> riskAstar(const planning::OccupancyGrid& g, planning::Cell s, planning::Cell t,
                                       const std::function<double(Vec2)>& risk, double w) {
  planning::CostLayers layers;
  layers.push_back(std::make_shared<planning::EnterCellCost>("risk", [&](planning::Cell c) {
    return 1.0 + w * (risk ? std::clamp(risk(g.cellCenter(c)), 0.0, 1.0) : 0.0);
  }));
  return planning::astar(g, s, t, layers);
}

}  // namespace

TEST(RiskLookup, LooksUpTheLevelUpperBoundOfTheCellAndZeroOffTheMap) {
  std::vector<std::uint8_t> levels(4 * 3, 0);
  levels[1 * 4 + 2] = 5;  // cell (2, 1)
  levels[0] = 10;
  const auto f = risk::riskLookupOf(riskMap(4, 3, 0.5, {-1.0, 2.0}, 10, levels));
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
  EXPECT_FALSE(risk::riskLookupOf(m));
  m = riskMap(4, 3, 0.5, {}, 4, levels);
  m.runs.front().level = 9;
  EXPECT_FALSE(risk::riskLookupOf(m));
  m = riskMap(4, 3, 0.0, {}, 4, levels);
  EXPECT_FALSE(risk::riskLookupOf(m));
  m = riskMap(4, 3, 0.5, {}, 4, levels);
  m.levels = 0;
  EXPECT_FALSE(risk::riskLookupOf(m));
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
    std::vector<test::StraightReleases> releases;
    for (int i = 0; i < 12; ++i) {
      agent::AgentParams p;
      p.id = "r" + std::to_string(i);
      p.start = {1.0 + i, 1.0, 0.5};
      p.localPlanner = i % 2 == 0 ? "dwa" : "follow";
      agents.push_back(std::make_unique<agent::Agent>(p, grid));
      releases.emplace_back(p.id);
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
      for (std::size_t i = 0; i < outs.size(); ++i) {
        log.push_back(outs[i].command);
        if (outs[i].traffic) {
          if (auto r = releases[i].onProgress(*outs[i].traffic)) {
            agents[i]->onRelease(*r);
          }
        }
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
