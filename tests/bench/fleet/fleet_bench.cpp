// Allocation latency (Hungarian vs greedy, same instances, same run) and durable task intake.
#include <benchmark/benchmark.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <random>
#include <thread>

#include "fleet/fleet/allocator.hpp"
#include "fleet/fleet/dispatcher.hpp"
#include "fleet/fleet/sqlite_task_store.hpp"

namespace fleet {
namespace {

constexpr std::int64_t kSec = 1'000'000'000;

/// prefix + n, built by appending: GCC 12 reports a false -Wrestrict on "literal" + std::string.
std::string numbered(std::string prefix, std::size_t n, const char* suffix = "") {
  prefix += std::to_string(n);
  prefix += suffix;
  return prefix;
}

/// A 200 m × 100 m site with 40 pickups, 20 dropoffs, 10 chargers; robots anywhere on it.
struct Site {
  StationMap stations;
  std::vector<const Station*> pickups, dropoffs;

  explicit Site(std::mt19937& rng) {
    std::uniform_real_distribution<double> x(0.0, 200.0), y(0.0, 100.0);
    auto add = [&](const std::string& prefix, int n, StationKind k) {
      for (int i = 0; i < n; ++i) {
        (void)stations.add({numbered(prefix, static_cast<std::size_t>(i)),
                            {x(rng), y(rng), 0.0},
                            static_cast<std::uint8_t>(k)});
      }
    };
    add("P-", 40, StationKind::Pickup);
    add("D-", 20, StationKind::Dropoff);
    add("C-", 10, StationKind::Charging);
    pickups = stations.ofKind(StationKind::Pickup);
    dropoffs = stations.ofKind(StationKind::Dropoff);
  }

  /// Straight line at 1 m/s: robot → pickup → dropoff (or → station).
  [[nodiscard]] TravelCost travel() const {
    return [this](const RobotInfo& r, const Task& t) {
      auto dist = [](const Pose2& a, const Pose2& b) { return std::hypot(a.x - b.x, a.y - b.y); };
      if (t.kind == TaskKind::Transport) {
        const Pose2& p = stations.find(t.pickup)->pose;
        return dist(r.pose, p) + dist(p, stations.find(t.dropoff)->pose);
      }
      const Station* s = stations.find(t.station);
      return s == nullptr ? 0.0 : dist(r.pose, s->pose);
    };
  }

  /// The same costs resolved once per task: station look-ups happen T times, not T×R.
  [[nodiscard]] TravelModel travelModel() const {
    return [this](const Task& t) -> RobotTravel {
      const bool transport = t.kind == TaskKind::Transport;
      const Station* first = stations.find(transport ? t.pickup : t.station);
      if (first == nullptr) {
        return [](const RobotInfo&) { return 0.0; };
      }
      const Pose2 p = first->pose;
      const double leg = transport ? std::hypot(p.x - stations.find(t.dropoff)->pose.x,
                                                p.y - stations.find(t.dropoff)->pose.y)
                                   : 0.0;
      return [p, leg](const RobotInfo& r) { return std::hypot(r.pose.x - p.x, r.pose.y - p.y) + leg; };
    };
  }

  std::vector<Task> tasks(std::mt19937& rng, std::size_t n, const std::string& prefix) const {
    std::vector<Task> out(n);
    for (std::size_t i = 0; i < n; ++i) {
      out[i].id = numbered(prefix, i);
      out[i].pickup = pickups[rng() % pickups.size()]->name;
      out[i].dropoff = dropoffs[rng() % dropoffs.size()]->name;
      out[i].priority = static_cast<std::int32_t>(rng() % 3);
      out[i].deadlineNs = rng() % 2 == 0 ? static_cast<std::int64_t>(60 + rng() % 600) * kSec : 0;
    }
    return out;
  }

  static std::vector<RobotInfo> robots(std::mt19937& rng, std::size_t n) {
    std::uniform_real_distribution<double> x(0.0, 200.0), y(0.0, 100.0), b(0.1, 1.0);
    std::vector<RobotInfo> out(n);
    for (std::size_t j = 0; j < n; ++j) {
      out[j].id = numbered("r", j);
      out[j].pose = {x(rng), y(rng), 0.0};
      out[j].battery = b(rng);
    }
    return out;
  }
};

double quantile(std::vector<double> v, double q) {
  if (v.empty()) {
    return 0.0;
  }
  std::sort(v.begin(), v.end());
  const auto idx = static_cast<std::size_t>(std::ceil(q * static_cast<double>(v.size()))) - 1;
  return v[std::min(idx, v.size() - 1)];
}

double objective(const CostMatrix& c, const std::vector<Assignment>& as) {
  double s = 0.0;
  for (const auto& a : as) {
    s += c.at(a.task, a.robot);
  }
  return s;
}

/// Both allocators on the same instances in the same run; times each call (cost matrix included)
/// and reports p50/p99 in ms, plus greedy's objective relative to the optimum.
void BM_Assign(benchmark::State& state) {
  const auto nTasks = static_cast<std::size_t>(state.range(0));
  const auto nRobots = static_cast<std::size_t>(state.range(1));
  const bool greedy = state.range(2) != 0;
  const bool pairFn = state.range(3) != 0;
  std::mt19937 rng(42);
  const Site site(rng);
  constexpr int kInstances = 16;
  std::vector<std::vector<Task>> tasks;
  std::vector<std::vector<RobotInfo>> robots;
  for (int i = 0; i < kInstances; ++i) {
    tasks.push_back(site.tasks(rng, nTasks, "t"));
    robots.push_back(Site::robots(rng, nRobots));
  }
  const HungarianAllocator hungarian;
  const GreedyAllocator greedyAlloc;
  const Allocator& alloc = greedy ? static_cast<const Allocator&>(greedyAlloc) : hungarian;
  const TravelModel travel = pairFn ? perPair(site.travel()) : site.travelModel();
  std::vector<double> ms;
  std::size_t k = 0;
  std::size_t assigned = 0;
  for (auto _ : state) {
    const auto t0 = std::chrono::steady_clock::now();
    auto as = alloc.assign(tasks[k % kInstances], robots[k % kInstances], travel, 0);
    const auto t1 = std::chrono::steady_clock::now();
    benchmark::DoNotOptimize(as.data());
    assigned += as.size();
    ms.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
    ++k;
  }
  // Quality on every instance (outside the timed loop): greedy objective minus optimal, in seconds
  // of effective cost per task, and the share of instances where greedy was worse.
  double gap = 0.0;
  int worse = 0;
  for (int i = 0; i < kInstances; ++i) {
    const auto c = effectiveCosts(tasks[i], robots[i], travel, AllocationPolicy{}, 0);
    const double h = objective(c, hungarian.assign(tasks[i], robots[i], travel, 0));
    const double g = objective(c, greedyAlloc.assign(tasks[i], robots[i], travel, 0));
    gap += (g - h) / static_cast<double>(nTasks);
    worse += g > h + 1e-6 ? 1 : 0;
  }
  state.counters["p50_ms"] = quantile(ms, 0.50);
  state.counters["p99_ms"] = quantile(ms, 0.99);
  state.counters["assigned"] = static_cast<double>(assigned) / static_cast<double>(k);
  state.counters["greedy_gap_s_per_task"] = gap / kInstances;
  state.counters["greedy_worse_share"] = static_cast<double>(worse) / kInstances;
  state.SetLabel(std::string(greedy ? "greedy" : "hungarian") + (pairFn ? ", per-pair cost fn" : ""));
}
BENCHMARK(BM_Assign)
    ->ArgNames({"tasks", "robots", "greedy", "pairfn"})
    ->ArgsProduct({{100}, {1000}, {0, 1}, {0, 1}})
    ->ArgsProduct({{10, 50, 200}, {1000}, {0, 1}, {0}})
    ->ArgsProduct({{100}, {200, 5000}, {0, 1}, {0}})
    ->ArgsProduct({{1000}, {1000}, {0, 1}, {0}})
    ->Unit(benchmark::kMillisecond)
    ->MinTime(1.0);

/// The solver alone on a random dense matrix (no cost evaluation): how it grows with size.
void BM_HungarianSolve(benchmark::State& state) {
  const auto rows = static_cast<std::size_t>(state.range(0));
  const auto cols = static_cast<std::size_t>(state.range(1));
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> u(0.0, 300.0);
  CostMatrix c(rows, cols);
  for (auto& x : c.v) {
    x = u(rng);
  }
  for (auto _ : state) {
    auto s = solveHungarian(c);
    benchmark::DoNotOptimize(s.data());
  }
}
BENCHMARK(BM_HungarianSolve)
    ->ArgNames({"rows", "cols"})
    ->Args({100, 1000})
    ->Args({50, 1000})
    ->Args({200, 1000})
    ->Args({100, 5000})
    ->Args({1000, 1000})
    ->Unit(benchmark::kMillisecond);

std::string benchDir() {
  const char* env = std::getenv("FLEET_BENCH_DB_DIR");
  std::filesystem::path base = env != nullptr ? env : std::filesystem::temp_directory_path().string();
  return (base / numbered("fleet-bench-", static_cast<std::size_t>(::getpid()))).string();
}

/// Durable intake: `batch` tasks per commit (1 = one transaction per task), synchronous FULL or NORMAL.
void BM_Submit(benchmark::State& state) {
  const auto batch = static_cast<std::size_t>(state.range(0));
  const bool full = state.range(1) != 0;
  const std::string dir = benchDir();
  std::filesystem::create_directories(dir);
  const std::string path = dir + "/tasks.db";
  std::filesystem::remove(path);
  std::filesystem::remove(path + "-wal");
  std::filesystem::remove(path + "-shm");
  auto store = SqliteTaskStore::open(
      {path, full ? SqliteTaskStoreOptions::Sync::Full : SqliteTaskStoreOptions::Sync::Normal});
  if (!store) {
    state.SkipWithError(store.error().message.c_str());
    return;
  }
  std::mt19937 rng(1);
  const Site site(rng);
  std::size_t next = 0;
  std::size_t total = 0;
  std::vector<double> ms;
  for (auto _ : state) {
    state.PauseTiming();
    auto tasks = site.tasks(rng, batch, numbered("b", next++, "-"));
    state.ResumeTiming();
    const auto t0 = std::chrono::steady_clock::now();
    auto rs = (*store)->submitBatch(tasks, 1);
    ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    if (!rs.front()) {
      state.SkipWithError(rs.front().error().message.c_str());
      break;
    }
    total += batch;
  }
  state.counters["tasks_per_s"] = benchmark::Counter(static_cast<double>(total), benchmark::Counter::kIsRate);
  state.counters["commit_p99_ms"] = quantile(ms, 0.99);
  state.SetLabel(full ? "synchronous=FULL" : "synchronous=NORMAL");
  store->reset();
  std::filesystem::remove_all(dir);
}
BENCHMARK(BM_Submit)
    ->ArgNames({"batch", "full"})
    ->ArgsProduct({{1, 10, 100, 1000}, {1, 0}})
    ->UseRealTime()  // fsync-bound: the rate must be per wall-clock second
    ->Unit(benchmark::kMillisecond)
    ->MinTime(2.0);

/// Offered load: tasks arrive at `rate` per second (as DDS samples would); the intake loop takes
/// everything that has arrived and stores it in one commit, so batches grow with the commit time.
/// Reports achieved throughput, arrival → durable latency, and the mean batch.
void BM_IntakeAtRate(benchmark::State& state) {
  const double rate = static_cast<double>(state.range(0));
  const bool full = state.range(1) != 0;
  const std::string dir = benchDir();
  std::filesystem::create_directories(dir);
  auto store = SqliteTaskStore::open(
      {dir + "/tasks.db", full ? SqliteTaskStoreOptions::Sync::Full : SqliteTaskStoreOptions::Sync::Normal});
  if (!store) {
    state.SkipWithError(store.error().message.c_str());
    return;
  }
  std::mt19937 rng(3);
  const Site site(rng);
  const auto pool = site.tasks(rng, 200'000, "a");
  using Clock = std::chrono::steady_clock;
  std::vector<double> latencyMs;
  std::size_t taken = 0;
  std::size_t commits = 0;
  double seconds = 0.0;
  for (auto _ : state) {
    const auto start = Clock::now();
    const std::size_t base = taken;
    // Two seconds of offered load per iteration.
    while (true) {
      const double elapsed = std::chrono::duration<double>(Clock::now() - start).count();
      if (elapsed >= 2.0 || taken >= pool.size()) {
        seconds += elapsed;
        break;
      }
      const auto due = base + static_cast<std::size_t>(elapsed * rate);
      if (due <= taken) {
        std::this_thread::sleep_for(std::chrono::microseconds(100));  // idle like a blocked reader
        continue;
      }
      const std::vector<Task> batch(pool.begin() + static_cast<std::ptrdiff_t>(taken),
                                    pool.begin() + static_cast<std::ptrdiff_t>(std::min(due, pool.size())));
      auto rs = (*store)->submitBatch(batch, 1);
      const double done = std::chrono::duration<double>(Clock::now() - start).count();
      for (std::size_t i = taken; i < taken + batch.size(); ++i) {
        const double arrived = static_cast<double>(i - base) / rate;
        latencyMs.push_back((done - arrived) * 1e3);
      }
      taken += batch.size();
      ++commits;
    }
  }
  state.counters["offered_per_s"] = rate;
  state.counters["stored_per_s"] = static_cast<double>(taken) / seconds;
  state.counters["latency_p99_ms"] = quantile(latencyMs, 0.99);
  state.counters["latency_p50_ms"] = quantile(latencyMs, 0.50);
  state.counters["mean_batch"] =
      static_cast<double>(taken) / static_cast<double>(std::max<std::size_t>(commits, 1));
  state.SetLabel(full ? "synchronous=FULL" : "synchronous=NORMAL");
  store->reset();
  std::filesystem::remove_all(dir);
}
BENCHMARK(BM_IntakeAtRate)
    ->ArgNames({"rate", "full"})
    ->ArgsProduct({{2000, 5000, 20000}, {1, 0}})
    ->Iterations(1)
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);

/// One dispatcher tick over 100 new tasks and 1,000 idle robots: allocation plus the durable commit
/// of the 100 assignments — the manager's assignment latency.
void BM_DispatchTick(benchmark::State& state) {
  const std::string dir = benchDir();
  std::filesystem::create_directories(dir);
  auto store = SqliteTaskStore::open({dir + "/tasks.db"});
  if (!store) {
    state.SkipWithError(store.error().message.c_str());
    return;
  }
  std::mt19937 rng(5);
  Site site(rng);
  const TravelModel travel = site.travelModel();
  std::vector<double> ms;
  std::size_t round = 0;
  for (auto _ : state) {
    state.PauseTiming();
    Dispatcher d(**store, site.stations, travel);
    for (const auto& r : Site::robots(rng, 1000)) {
      d.onRobotState({r.id, r.pose, 0.9, 0});
    }
    d.submit(site.tasks(rng, 100, numbered("k", round++, "-")), 0);
    state.ResumeTiming();
    const auto t0 = std::chrono::steady_clock::now();
    auto out = d.tick(1);
    ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    if (out.assignments.size() != 100) {
      state.SkipWithError("not every task was assigned");
      break;
    }
  }
  state.counters["p50_ms"] = quantile(ms, 0.50);
  state.counters["p99_ms"] = quantile(ms, 0.99);
  store->reset();
  std::filesystem::remove_all(dir);
}
BENCHMARK(BM_DispatchTick)->Unit(benchmark::kMillisecond)->MinTime(2.0);

/// A dispatcher tick with station admission at 300 robots: 200 tasks under way (robots spread over
/// the site), 1,000 waiting, 100 idle robots, every station's line 3 places. Arg 0: slots counted
/// now (StationLoad::Phase); arg 1: by predicted arrival (StationLoad::Arrival, straight lines at
/// 1 m/s, 4 s of dock motion). The ratio is what booking every robot's arrival costs.
void BM_AdmissionTick(benchmark::State& state) {
  const bool byArrival = state.range(0) == 1;
  const std::string dir = benchDir();
  std::filesystem::create_directories(dir);
  std::mt19937 rng(5);
  Site site(rng);
  DispatcherConfig cfg;
  cfg.stationLoad = byArrival ? StationLoad::Arrival : StationLoad::Phase;
  for (const Station* st : site.stations.all()) {
    cfg.stationCapacities[st->name] = 3;
  }
  const auto at = [&site](const std::string& name) { return site.stations.find(name)->pose; };
  cfg.stationTimes.toStation = [at](Vec2 from, const std::string& name) {
    const Pose2 p = at(name);
    return std::hypot(from.x - p.x, from.y - p.y);
  };
  cfg.stationTimes.between = [at](const std::string& a, const std::string& b) {
    return std::hypot(at(a).x - at(b).x, at(a).y - at(b).y);
  };
  cfg.stationTimes.dockMove = [](const std::string&) { return 4.0; };
  std::vector<double> ms;
  std::size_t round = 0;
  for (auto _ : state) {
    state.PauseTiming();
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    auto store = SqliteTaskStore::open({dir + "/tasks.db"});
    if (!store) {
      state.SkipWithError(store.error().message.c_str());
      return;
    }
    Dispatcher d(**store, site.stations, site.travelModel(), cfg);
    const auto robots = Site::robots(rng, 300);
    for (std::size_t j = 0; j < robots.size(); ++j) {
      d.onRobotState({robots[j].id, robots[j].pose, 0.9, 0});
    }
    d.submit(site.tasks(rng, 200, numbered("a", round, "-")), 0);
    (void)d.tick(1);  // as many under way as their stations' lines take
    d.submit(site.tasks(rng, 1000, numbered("w", round++, "-")), 2);
    state.ResumeTiming();
    const auto t0 = std::chrono::steady_clock::now();
    auto out = d.tick(3);
    ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    benchmark::DoNotOptimize(out.assignments.data());
    state.counters["active"] = static_cast<double>(d.activeCount());
  }
  state.counters["p50_ms"] = quantile(ms, 0.50);
  std::filesystem::remove_all(dir);
}
BENCHMARK(BM_AdmissionTick)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->MinTime(2.0);

}  // namespace
}  // namespace fleet

BENCHMARK_MAIN();
