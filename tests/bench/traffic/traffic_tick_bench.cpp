// Traffic manager tick ("Scale, one core"): TrafficControl::update() driving the virtual fleet
// (libs/traffic virtual_fleet) on the warehouse `fleetctl loadtest --robots N` generates, for 100 /
// 300 / 1,000 robots on the site for that many, 20 simulated seconds (FLEET_TICK_SECONDS to
// change), seed 1, with admission by station slots (everyone:0) and with every robot given a task
// from the start (everyone:1). One iteration is one whole run; its update p50 / p99 are the counters.
// Targets: p99 <= 50 ms at 300 robots and <= 200 ms at 1,000 on one core.
//
// BM_DockDwellTables: what a robot dwelling at a dock costs the goal tables on the site for 300
// robots: 300 robots stand still, each with a station's dock as its goal, their tables read at
// their node and its neighbours; one iteration blocks the nodes round one dock (a robot arrives),
// reads every table again, unblocks them (it leaves) and reads again. repair:0 restarts every table
// that had settled a changed node (the reference), repair:1 repairs it in place (the default).
//
// core:1 runs BM_TrafficTick on the timed core (TrafficOptions::core = Sipp) at 100 and 300 robots.
// BM_PrioritizedPlan: one plan of the timed core for 20 / 100 / 300 robots standing on random nodes
// of the site for that many, each with a random dock as its goal, every robot searched (no plan
// kept: reuseSlack < 0), the goals' heuristics and the turns already computed by a first plan: what
// a re-plan of everyone costs as robots are added.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <random>
#include <stdexcept>

#include "fleet/traffic/distance_table.hpp"
#include "fleet/traffic/prioritized_planner.hpp"

#include "fleet/site/site_loader.hpp"
#include "fleet/traffic/roadmap.hpp"
#include "fleet/traffic/virtual_fleet.hpp"
#include "scenario_gen.hpp"
#include "scenario_tasks.hpp"

using namespace fleet;

namespace {

/// The site `fleetctl loadtest --robots N` writes (small warehouse template, default seed).
site::Site siteFor(int robots) {
  const std::string templPath = FLEET_SOURCE_DIR "/sim/scenarios/small_warehouse.json";
  std::ifstream in(templPath);
  if (!in) {
    throw std::runtime_error("cannot read " + templPath);
  }
  nlohmann::json templ = nlohmann::json::parse(in);
  templ = ctl::inlineSiteRobot(templ, templPath);
  auto g = ctl::generateScenario(templ, {.robots = robots, .humans = 0, .durationS = 60.0});
  if (!g) {
    throw std::runtime_error(g.error().message);
  }
  auto [site, rest] = ctl::splitSite(*g);
  return site::parseSite(site, "generated site for " + std::to_string(robots) + " robots",
                         FLEET_SOURCE_DIR "/sim/scenarios");
}

void BM_TrafficTick(benchmark::State& state) {
  const auto robots = static_cast<int>(state.range(0));
  const site::Site site = siteFor(robots);
  traffic::Roadmap roadmap = traffic::buildRoadmap(site, {});
  const char* seconds = std::getenv("FLEET_TICK_SECONDS");
  traffic::VirtualFleetOptions o;
  o.robots = static_cast<std::size_t>(robots);
  o.duration = seconds != nullptr ? std::atof(seconds) : 20.0;
  o.seed = 1;
  // 0: admission by station slots (the default: ~50 of 300 robots working); 1: none, every robot
  // has a task from the start (what the tick must carry when the stations do not limit the fleet).
  o.admission = state.range(1) == 0 ? traffic::Admission::Slots : traffic::Admission::None;
  o.traffic.core = state.range(2) == 0 ? traffic::PlannerCore::Pibt : traffic::PlannerCore::Sipp;
  traffic::VirtualFleetResult r;
  for (auto _ : state) {
    r = traffic::runVirtualFleet(roadmap, o);
  }
  state.counters["nodes"] = static_cast<double>(roadmap.graph.size());
  state.counters["update_p50_ms"] = r.updateP50Ms;
  state.counters["update_p99_ms"] = r.updateP99Ms;
  state.counters["planner_steps"] = static_cast<double>(r.plannerSteps);
  state.counters["detours"] = static_cast<double>(r.detours);
  state.counters["tasks_done"] = static_cast<double>(r.tasksDone);
  state.counters["searches"] = static_cast<double>(r.search.searches);
  state.counters["search_failures"] = static_cast<double>(r.search.failures);
  state.counters["expanded"] = static_cast<double>(r.search.expanded);
  state.counters["goal_tables"] = static_cast<double>(r.search.heuristics);
}
BENCHMARK(BM_TrafficTick)
    ->ArgNames({"robots", "everyone", "core"})
    ->ArgsProduct({{100, 300, 1000}, {0, 1}, {0}})
    ->Args({100, 0, 1})
    ->Args({300, 0, 1})
    ->Iterations(1)
    ->Unit(benchmark::kSecond);

void BM_DockDwellTables(benchmark::State& state) {
  const site::Site site = siteFor(300);
  const traffic::Roadmap roadmap = traffic::buildRoadmap(site, {});
  const traffic::Graph& g = roadmap.graph;
  traffic::DistanceTable tables(g);
  tables.setOnChange(state.range(0) == 0 ? traffic::DistanceTable::OnChange::kRestart
                                         : traffic::DistanceTable::OnChange::kRepair);
  // Each dock with what a robot on it covers: the nodes within a robot's width of it.
  std::vector<std::vector<traffic::NodeId>> covers;
  std::vector<traffic::NodeId> docks;
  for (const auto& st : roadmap.stations) {
    if (st.dock == traffic::kNoNode) {
      continue;
    }
    docks.push_back(st.dock);
    auto& cover = covers.emplace_back();
    const Vec2 c = g.position(st.dock);
    for (std::size_t v = 0; v < g.size(); ++v) {
      const Vec2 p = g.position(static_cast<traffic::NodeId>(v));
      if ((p.x - c.x) * (p.x - c.x) + (p.y - c.y) * (p.y - c.y) <= 0.7 * 0.7) {
        cover.push_back(static_cast<traffic::NodeId>(v));
      }
    }
  }
  std::mt19937_64 rng(1);
  std::uniform_int_distribution<std::size_t> anyNode(0, g.size() - 1);
  std::uniform_int_distribution<std::size_t> anyDock(0, docks.size() - 1);
  std::vector<traffic::NodeId> at;
  std::vector<traffic::NodeId> goal;
  while (at.size() < 300) {
    const auto v = static_cast<traffic::NodeId>(anyNode(rng));
    if (g.isOpen(v) && !g.edges(v).empty()) {
      at.push_back(v);
      goal.push_back(docks[anyDock(rng)]);
    }
  }
  tables.reserve(docks.size() + 1);
  const auto read = [&] {
    float sum = 0.0F;
    for (std::size_t i = 0; i < at.size(); ++i) {
      sum += tables.distance(at[i], goal[i]) > 0.0F ? 1.0F : 0.0F;
      for (const traffic::Edge& e : g.edges(at[i])) {
        sum += tables.distance(e.to, goal[i]) > 0.0F ? 1.0F : 0.0F;
      }
    }
    benchmark::DoNotOptimize(sum);
  };
  read();
  const std::uint64_t computed0 = tables.computed();
  const std::uint64_t repaired0 = tables.repaired();
  std::size_t next = 0;
  for (auto _ : state) {
    const auto& cover = covers[(next++ * 37) % covers.size()];  // spread over the site's docks
    for (const traffic::NodeId v : cover) {
      tables.setBlocked(v, true);
    }
    read();
    for (const traffic::NodeId v : cover) {
      tables.setBlocked(v, false);
    }
    read();
  }
  const auto n = static_cast<double>(state.iterations());
  state.counters["nodes"] = static_cast<double>(g.size());
  state.counters["docks"] = static_cast<double>(docks.size());
  state.counters["restarts_per_dwell"] = static_cast<double>(tables.computed() - computed0) / n;
  state.counters["repairs_per_dwell"] = static_cast<double>(tables.repaired() - repaired0) / n;
}
BENCHMARK(BM_DockDwellTables)
    ->ArgName("repair")
    ->Arg(0)
    ->Arg(1)
    ->Iterations(40)
    ->Unit(benchmark::kMillisecond);

void BM_PrioritizedPlan(benchmark::State& state) {
  const auto robots = static_cast<std::size_t>(state.range(0));
  const site::Site site = siteFor(static_cast<int>(robots));
  const traffic::Roadmap roadmap = traffic::buildRoadmap(site, {});
  const auto& g = roadmap.graph;
  std::mt19937_64 rng(1);
  std::uniform_int_distribution<traffic::NodeId> node(0, static_cast<traffic::NodeId>(g.size()) - 1);
  std::vector<traffic::NodeId> docks;
  for (const auto& st : roadmap.stations) {
    if (st.dock != traffic::kNoNode)
      docks.push_back(st.dock);
  }
  std::uniform_int_distribution<std::size_t> dock(0, docks.size() - 1);
  std::vector<traffic::PlanRequest> req;
  std::vector<traffic::NodeId> taken;
  while (req.size() < robots) {
    const traffic::NodeId v = node(rng);
    if (std::any_of(taken.begin(), taken.end(),
                    [&](traffic::NodeId u) { return u == v || g.conflicting(u, v); }))
      continue;
    taken.push_back(v);
    traffic::PlanRequest r;
    r.at = v;
    r.goal = docks[dock(rng)];
    r.waiting = static_cast<double>(req.size());
    req.push_back(r);
  }
  traffic::PrioritizedPlanner planner(g,
                                      [&roadmap](traffic::NodeId a, traffic::NodeId b, traffic::NodeId c) {
                                        return roadmap.extraTurn(a, b, c);
                                      },
                                      {.reuseSlack = -1.0});
  planner.plan(req);  // the heuristics and turns, once
  const auto before = planner.stats();
  for (auto _ : state)
    benchmark::DoNotOptimize(planner.plan(req));
  const auto& after = planner.stats();
  const auto plans = static_cast<double>(after.plans - before.plans);
  state.counters["nodes"] = static_cast<double>(g.size());
  state.counters["failures"] = static_cast<double>(after.failures - before.failures) / plans;
  state.counters["yields"] = static_cast<double>(after.yields - before.yields) / plans;
}
BENCHMARK(BM_PrioritizedPlan)->ArgName("robots")->Arg(20)->Arg(100)->Arg(300)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
