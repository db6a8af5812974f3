// Cost of one SensorFrame in the agent's localizer with and without the laser-line updates
// (extraction, matching against the site's wall faces, the EKF updates): every robot of a scenario,
// standing at its start, scanned by the simulator (72 rays, people and robots included).

#include <benchmark/benchmark.h>

#include <map>
#include <memory>
#include <string>
#include <vector>

#include "fleet/sim/world.hpp"
#include "fleet/site/wall_segments.hpp"
#include "localizer.hpp"

using namespace fleet;

namespace {

struct Setup {
  std::vector<agent::SensorReading> frames;
  std::vector<Pose2> starts;
  std::shared_ptr<const std::vector<estimation::MapSegment>> walls;
};

const Setup& setup(const std::string& name) {
  static std::map<std::string, Setup> cache;
  auto& s = cache[name];
  if (!s.frames.empty()) {
    return s;
  }
  sim::World w(sim::loadScenario(FLEET_SOURCE_DIR "/sim/scenarios/" + name + ".json"));
  planning::OccupancyGrid grid(w.scenario().map.width, w.scenario().map.height, w.scenario().map.resolution,
                               w.scenario().map.origin);
  for (int y = 0; y < grid.height(); ++y) {
    for (int x = 0; x < grid.width(); ++x) {
      if (w.scenario().map.blocked(x, y)) {
        grid.setBlocked({x, y});
      }
    }
  }
  auto walls = std::make_shared<std::vector<estimation::MapSegment>>();
  for (const auto& f : site::wallSegments(grid, agent::agentLineExtraction().minLength)) {
    walls->push_back({f.a, f.b, f.normal});
  }
  s.walls = walls;
  for (const auto& r : w.sensorFrames(true)) {
    agent::SensorReading a;
    a.stampNs = 100'000'000;
    a.compassValid = r.compassValid;
    a.compass = r.compass;
    a.angleMin = r.angleMin;
    a.angleIncrement = r.angleIncrement;
    a.rangeMax = r.rangeMax;
    a.ranges = r.ranges;
    s.frames.push_back(a);
    s.starts.push_back(w.robots()[r.robot].pose);
  }
  return s;
}

void BM_LocalizerFrame(benchmark::State& state, const std::string& scenario) {
  const Setup& s = setup(scenario);
  const bool lines = state.range(0) != 0;
  std::vector<agent::Localizer> locs;
  for (const Pose2& p : s.starts) {
    agent::LocalizerParams lp;
    lp.start = p;
    lp.walls = s.walls;
    lp.lineUpdates = lines;
    locs.emplace_back(lp);
  }
  std::size_t i = 0;
  std::int64_t stamp = 0;
  for (auto _ : state) {
    const std::size_t k = i++ % locs.size();
    agent::SensorReading f = s.frames[k];
    f.stampNs = (stamp += 100'000'000);
    locs[k].onReading(f);
    benchmark::DoNotOptimize(locs[k].pose());
  }
  std::uint64_t fused = 0;
  for (const auto& l : locs) {
    fused += l.lineStats().accepted;
  }
  state.counters["lines_per_frame"] = static_cast<double>(fused) / static_cast<double>(state.iterations());
  state.counters["walls"] = static_cast<double>(s.walls->size());
}

BENCHMARK_CAPTURE(BM_LocalizerFrame, small_warehouse, std::string("small_warehouse"))->Arg(0)->Arg(1);
BENCHMARK_CAPTURE(BM_LocalizerFrame, large_warehouse, std::string("large_warehouse"))->Arg(0)->Arg(1);

}  // namespace

BENCHMARK_MAIN();
