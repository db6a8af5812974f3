// Traffic manager tick ("Scale, one core"): TrafficControl::update() driving the virtual fleet
// (libs/traffic virtual_fleet) on the warehouse `fleetctl loadtest --robots N` generates, for 100 /
// 300 / 1,000 robots on the site for that many, 20 simulated seconds (FLEET_TICK_SECONDS to
// change), seed 1, with admission by station slots (everyone:0) and with every robot given a task
// from the start (everyone:1). One iteration is one whole run; its update p50 / p99 are the counters.
// Targets: p99 <= 50 ms at 300 robots and <= 200 ms at 1,000 on one core.
#include <benchmark/benchmark.h>

#include <cstdlib>
#include <fstream>
#include <stdexcept>

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
}
BENCHMARK(BM_TrafficTick)
    ->ArgNames({"robots", "everyone"})
    ->ArgsProduct({{100, 300, 1000}, {0, 1}})
    ->Iterations(1)
    ->Unit(benchmark::kSecond);

}  // namespace

BENCHMARK_MAIN();
