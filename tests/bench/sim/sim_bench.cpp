// One simulation step (robot kinematics + social-force humans + contact checks, optionally a range
// scan for every robot) at warehouse scale. Real-time factor = dt / step time (dt = 0.1 s, 10 Hz).

#include <benchmark/benchmark.h>

#include <cmath>
#include <map>
#include <memory>

#include "fleet/sim/world.hpp"

using namespace fleet;
using namespace fleet::sim;

namespace {

// A generated warehouse big enough for `robots` robots on a 2 m lattice plus `humans` people.
std::unique_ptr<World> makeWorld(int robots, int humans, int rays) {
  const int cells = robots + humans > 4000 ? 700 : 400;  // 0.5 m cells: 200 m / 350 m square
  nlohmann::json j;
  j["name"] = "bench";
  j["seed"] = 1;
  j["dt"] = 0.1;
  j["map"] = {{"warehouse",
               {{"width", cells},
                {"height", cells},
                {"margin", 8},
                {"shelf_width", 16},
                {"shelf_height", 2},
                {"aisle_x", 6},
                {"aisle_y", 6}}},
              {"resolution", 0.5}};
  j["robot_defaults"] = {{"radius", 0.3},
                         {"sensors", {{"rays", rays}, {"range_max", 8.0}, {"rate_hz", 10.0}}}};
  j["robots"] = nlohmann::json::array();
  if (robots > 0) {
    j["robot_fleet"] = {{"count", robots}, {"spacing", 2.0}};
  }
  j["humans"] = {{"count", humans}, {"stop_probability", 0.1}};
  auto w = std::make_unique<World>(parseScenario(j, "bench", "."));
  return w;
}

void drive(World& w) {
  const double k = static_cast<double>(w.step());
  for (std::size_t i = 0; i < w.robots().size(); ++i) {
    w.command(i, 0.6, 0.4 * std::sin(0.05 * k + static_cast<double>(i)));
  }
}

void runSteps(benchmark::State& state, int robots, int humans, int rays, bool scans) {
  auto w = makeWorld(robots, humans, rays);
  std::size_t beams = 0;
  for (auto _ : state) {
    drive(*w);
    w->advance();
    if (scans) {
      for (const auto& f : w->sensorFrames(true)) {
        beams += f.ranges.size();
      }
    }
    benchmark::ClobberMemory();
  }
  state.counters["robots"] = robots;
  state.counters["humans"] = static_cast<double>(w->humans().size());
  state.counters["rays"] = scans ? rays : 0;
  state.counters["beams/step"] =
      benchmark::Counter(static_cast<double>(beams) / static_cast<double>(state.iterations()));
  // Simulated seconds per wall second at dt = 0.1 s.
  state.counters["x_realtime"] =
      benchmark::Counter(0.1 * static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}

// The headline: 1,000 robots + 1,000 humans, 72-ray scans for every robot every step.
void BM_Step_1000R_1000H_72Rays(benchmark::State& s) {
  runSteps(s, 1000, 1000, 72, true);
}
BENCHMARK(BM_Step_1000R_1000H_72Rays)
    ->Unit(benchmark::kMillisecond)
    ->Repetitions(5)
    ->ReportAggregatesOnly(true);

// 10,000 agents, no scans (odometry/compass/landmarks/detections still off: kinematics, humans, contacts).
void BM_Step_10000Agents_NoScan(benchmark::State& s) {
  runSteps(s, 5000, 5000, 0, false);
}
BENCHMARK(BM_Step_10000Agents_NoScan)
    ->Unit(benchmark::kMillisecond)
    ->Repetitions(3)
    ->ReportAggregatesOnly(true);

// Growth with robots (72-ray scans, no humans), humans (no robots), rays (1,000 robots).
void BM_GrowRobots(benchmark::State& s) {
  runSteps(s, static_cast<int>(s.range(0)), 0, 72, true);
}
BENCHMARK(BM_GrowRobots)->Arg(100)->Arg(300)->Arg(1000)->Arg(3000)->Unit(benchmark::kMillisecond);

void BM_GrowHumans(benchmark::State& s) {
  runSteps(s, 0, static_cast<int>(s.range(0)), 0, false);
}
BENCHMARK(BM_GrowHumans)->Arg(100)->Arg(300)->Arg(1000)->Arg(3000)->Unit(benchmark::kMillisecond);

void BM_GrowRays(benchmark::State& s) {
  runSteps(s, 1000, 0, static_cast<int>(s.range(0)), true);
}
BENCHMARK(BM_GrowRays)->Arg(18)->Arg(36)->Arg(72)->Arg(144)->Arg(360)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
