// Planning benchmarks on the procedural 340 x 164 warehouse (38,756 free cells, the size
// of MovingAI warehouse-20-40-10-2-2): wavefront distance field, A* random queries (median and
// tail as counters), cached travel costs, and OMPL planners' time to a path within 1.1x of the
// grid-optimal (8-connected A*) length.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <ctime>
#include <random>

#include "fleet/planning/astar.hpp"
#include "fleet/planning/distance_field_cache.hpp"
#include "fleet/planning/ompl_planner.hpp"
#include "fleet/planning/wavefront.hpp"

using namespace fleet;
using namespace fleet::planning;

namespace {

const OccupancyGrid& warehouse() {
  static const OccupancyGrid g = makeWarehouseGrid();
  return g;
}

std::vector<Cell> freeCells(const OccupancyGrid& g) {
  std::vector<Cell> cells;
  for (std::size_t i = 0; i < g.size(); ++i) {
    if (g.cells()[i] == 0) {
      cells.push_back(g.cellOf(i));
    }
  }
  return cells;
}

void BM_WavefrontDistanceField(benchmark::State& state) {
  const auto& g = warehouse();
  const auto conn = state.range(0) == 4 ? Connectivity::Four : Connectivity::Eight;
  const auto cells = freeCells(g);
  std::mt19937 rng(1);
  std::uniform_int_distribution<std::size_t> pick(0, cells.size() - 1);
  for (auto _ : state) {
    const DistanceField f = computeDistanceField(g, cells[pick(rng)], conn);
    benchmark::DoNotOptimize(f.cost.data());
  }
  state.counters["free_cells"] = static_cast<double>(cells.size());
}
BENCHMARK(BM_WavefrontDistanceField)->Arg(4)->Arg(8)->Unit(benchmark::kMillisecond);

// 1000 random start/goal pairs per iteration, each timed: median and 90th percentile as counters.
void BM_AStarRandomQueries(benchmark::State& state) {
  const auto& g = warehouse();
  // Arg 0: octile heuristic only; Arg k > 0: max(octile, ALT with k landmarks).
  const int k = static_cast<int>(state.range(0));
  const LandmarkHeuristic lh = LandmarkHeuristic::build(g, Connectivity::Eight, k);
  const auto cells = freeCells(g);
  std::mt19937 rng(2);
  std::uniform_int_distribution<std::size_t> pick(0, cells.size() - 1);
  std::vector<double> us, cpuUs;
  double expanded = 0;
  auto cpuNow = [] {
    timespec ts{};
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return static_cast<double>(ts.tv_sec) * 1e6 + static_cast<double>(ts.tv_nsec) * 1e-3;
  };
  for (auto _ : state) {
    for (int q = 0; q < 1000; ++q) {
      const Cell a = cells[pick(rng)], b = cells[pick(rng)];
      const double c0 = cpuNow();
      const auto t0 = std::chrono::steady_clock::now();
      const auto r = astar(g, a, b, Connectivity::Eight, k > 0 ? &lh : nullptr);
      us.push_back(std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count());
      cpuUs.push_back(cpuNow() - c0);
      expanded += r ? r->expanded : 0;
    }
  }
  std::sort(us.begin(), us.end());
  std::sort(cpuUs.begin(), cpuUs.end());
  state.counters["median_us"] = us[us.size() / 2];
  state.counters["median_cpu_us"] = cpuUs[cpuUs.size() / 2];
  state.counters["p90_us"] = us[us.size() * 9 / 10];
  state.counters["max_us"] = us.back();
  state.counters["mean_expanded"] = expanded / static_cast<double>(us.size());
}
BENCHMARK(BM_AStarRandomQueries)->Arg(0)->Arg(8)->Arg(16)->Unit(benchmark::kMillisecond)->Iterations(3);

// A fleet asking travel costs from 200 robots to 50 stations, repeatedly: fields are cached.
void BM_DistanceFieldCacheTravelCosts(benchmark::State& state) {
  auto grid = std::make_shared<const OccupancyGrid>(warehouse());
  const auto cells = freeCells(*grid);
  std::mt19937 rng(3);
  std::uniform_int_distribution<std::size_t> pick(0, cells.size() - 1);
  std::vector<Cell> robots, stations;
  for (int k = 0; k < 200; ++k) {
    robots.push_back(cells[pick(rng)]);
  }
  for (int k = 0; k < 50; ++k) {
    stations.push_back(cells[pick(rng)]);
  }
  DistanceFieldCache cache(grid);
  double sum = 0;
  for (auto _ : state) {
    for (const Cell& s : stations) {
      for (const Cell& r : robots) {
        sum += cache.travelCost(r, s);
      }
    }
  }
  benchmark::DoNotOptimize(sum);
  state.SetItemsProcessed(state.iterations() * 200 * 50);
  state.counters["fields_computed"] = static_cast<double>(cache.computations());
}
BENCHMARK(BM_DistanceFieldCacheTravelCosts)->Unit(benchmark::kMillisecond);

// Time until an OMPL planner holds a path no longer than 1.1x the A* (8-connected) length, over a
// fixed set of long warehouse queries; budget 10 s per query.
void BM_OmplTimeTo1p1Optimal(benchmark::State& state) {
  const auto alg = static_cast<OmplAlgorithm>(state.range(0));
  const auto& g = warehouse();
  const auto cells = freeCells(g);
  std::mt19937 rng(4);
  std::uniform_int_distribution<std::size_t> pick(0, cells.size() - 1);
  std::vector<std::pair<Cell, Cell>> queries;
  while (queries.size() < 5) {
    const Cell a = cells[pick(rng)], b = cells[pick(rng)];
    if (std::hypot(a.x - b.x, a.y - b.y) > 150.0) {
      queries.push_back({a, b});
    }
  }
  std::vector<double> secs;
  int met = 0;
  for (auto _ : state) {
    for (const auto& [a, b] : queries) {
      const double optimal = astar(g, a, b).value().cost * g.resolution();
      OmplPlanner planner(
          {.algorithm = alg, .timeBudget = 10.0, .costThreshold = 1.1 * optimal, .simplify = false});
      const Vec2 pa = g.cellCenter(a), pb = g.cellCenter(b);
      const auto path = planner.plan(g, {pa.x, pa.y, 0}, {pb.x, pb.y, 0});
      secs.push_back(planner.lastStats().solveSeconds);
      met += (path && planner.lastStats().thresholdMet) ? 1 : 0;
    }
  }
  std::sort(secs.begin(), secs.end());
  state.counters["median_s"] = secs[secs.size() / 2];
  state.counters["max_s"] = secs.back();
  state.counters["met_fraction"] = static_cast<double>(met) / static_cast<double>(secs.size());
  state.SetLabel(OmplPlanner({.algorithm = alg}).name());
}
BENCHMARK(BM_OmplTimeTo1p1Optimal)
    ->Arg(static_cast<int>(OmplAlgorithm::RRTstar))
    ->Arg(static_cast<int>(OmplAlgorithm::PRMstar))
    ->Arg(static_cast<int>(OmplAlgorithm::InformedRRTstar))
    ->Iterations(1)
    ->Unit(benchmark::kSecond);

}  // namespace

BENCHMARK_MAIN();
