// Durable intake of the two TaskStore backends in one run: SQLite (WAL, synchronous=FULL) in a
// temporary directory, and PostgreSQL 15 (fsync on, synchronous_commit on) started by the bench on
// a Unix socket in a temporary directory on the same disk (tests/support/postgres_server.hpp).
// A task counts once submitBatch returned it stored: acknowledged, as the manager's TaskAck.

#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "fleet/fleet/postgres_task_store.hpp"
#include "fleet/fleet/sqlite_task_store.hpp"
#include "postgres_server.hpp"
#include "temp_dir.hpp"

namespace fleet {
namespace {

std::vector<Task> tasks(std::size_t n, const std::string& prefix) {
  std::vector<Task> out;
  out.reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    Task t;
    t.id = prefix;
    t.id += std::to_string(i);
    t.kind = TaskKind::Transport;
    t.pickup = "P-" + std::to_string(i % 40);
    t.dropoff = "D-" + std::to_string(i % 20);
    t.priority = static_cast<std::int32_t>(i % 3);
    out.push_back(std::move(t));
  }
  return out;
}

double quantile(std::vector<double> v, double q) {
  if (v.empty()) {
    return 0.0;
  }
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, static_cast<std::size_t>(q * static_cast<double>(v.size())))];
}

/// One server for the run, durable as in production.
test::PostgresServer& server() {
  static test::PostgresServer s(true);
  return s;
}

/// A fresh store of the backend (0 SQLite, 1 PostgreSQL); `dir` keeps SQLite's file.
std::unique_ptr<TaskStore> openStore(int backend, const test::TempDir& dir, benchmark::State& state) {
  if (backend == 0) {
    auto s = SqliteTaskStore::open({dir.file("tasks.db"), SqliteTaskStoreOptions::Sync::Full});
    if (!s) {
      state.SkipWithError(s.error().message.c_str());
      return nullptr;
    }
    state.SetLabel("sqlite synchronous=FULL");
    return std::move(*s);
  }
  if (!server().ok()) {
    state.SkipWithError(("PostgreSQL did not start: " + server().error()).c_str());
    return nullptr;
  }
  auto s = PostgresTaskStore::open({server().freshUrl()});
  if (!s) {
    state.SkipWithError(s.error().message.c_str());
    return nullptr;
  }
  state.SetLabel("postgresql fsync=on synchronous_commit=on");
  return std::move(*s);
}

/// Tasks arrive at `rate` per second for 3 s; the intake loop stores everything that has arrived
/// in one commit (as the manager does with a DDS batch), so batches grow with the commit time.
void BM_StoreIntakeAtRate(benchmark::State& state) {
  const int backend = static_cast<int>(state.range(0));
  const double rate = static_cast<double>(state.range(1));
  test::TempDir dir;
  auto store = openStore(backend, dir, state);
  if (!store) {
    return;
  }
  const auto pool = tasks(static_cast<std::size_t>(rate * 4), "a");
  using Clock = std::chrono::steady_clock;
  std::vector<double> latencyMs;
  std::size_t taken = 0;
  std::size_t commits = 0;
  double seconds = 0.0;
  for (auto _ : state) {
    const auto start = Clock::now();
    while (true) {
      const double elapsed = std::chrono::duration<double>(Clock::now() - start).count();
      if (elapsed >= 3.0 || taken >= pool.size()) {
        seconds += elapsed;
        break;
      }
      const auto due = std::min(static_cast<std::size_t>(elapsed * rate), pool.size());
      if (due <= taken) {
        std::this_thread::sleep_for(std::chrono::microseconds(100));
        continue;
      }
      const std::vector<Task> batch(pool.begin() + static_cast<std::ptrdiff_t>(taken),
                                    pool.begin() + static_cast<std::ptrdiff_t>(due));
      auto rs = store->submitBatch(batch, 1);
      if (!rs.front() || !rs.front()->created) {
        state.SkipWithError("a task was not stored");
        return;
      }
      const double done = std::chrono::duration<double>(Clock::now() - start).count();
      for (std::size_t i = taken; i < due; ++i) {
        latencyMs.push_back((done - static_cast<double>(i) / rate) * 1e3);
      }
      taken = due;
      ++commits;
    }
  }
  state.counters["offered_per_s"] = rate;
  state.counters["acked_per_s"] = static_cast<double>(taken) / seconds;
  state.counters["latency_p50_ms"] = quantile(latencyMs, 0.50);
  state.counters["latency_p99_ms"] = quantile(latencyMs, 0.99);
  state.counters["mean_batch"] =
      static_cast<double>(taken) / static_cast<double>(std::max<std::size_t>(commits, 1));
}
BENCHMARK(BM_StoreIntakeAtRate)
    ->ArgNames({"pg", "rate"})
    ->ArgsProduct({{0, 1}, {1000, 5000, 10000}})
    ->Iterations(1)
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);

/// Back to back: `batch` tasks per commit, as fast as the store takes them.
void BM_StoreSubmit(benchmark::State& state) {
  const int backend = static_cast<int>(state.range(0));
  const auto batch = static_cast<std::size_t>(state.range(1));
  test::TempDir dir;
  auto store = openStore(backend, dir, state);
  if (!store) {
    return;
  }
  std::size_t next = 0;
  std::size_t total = 0;
  std::vector<double> ms;
  for (auto _ : state) {
    state.PauseTiming();
    auto b = tasks(batch, "b" + std::to_string(next++) + "-");
    state.ResumeTiming();
    const auto t0 = std::chrono::steady_clock::now();
    auto rs = store->submitBatch(b, 1);
    ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    if (!rs.front()) {
      state.SkipWithError(rs.front().error().message.c_str());
      return;
    }
    total += batch;
  }
  state.counters["acked_per_s"] = benchmark::Counter(static_cast<double>(total), benchmark::Counter::kIsRate);
  state.counters["commit_p99_ms"] = quantile(ms, 0.99);
}
BENCHMARK(BM_StoreSubmit)
    ->ArgNames({"pg", "batch"})
    ->ArgsProduct({{0, 1}, {1, 100}})
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond)
    ->MinTime(2.0);

}  // namespace
}  // namespace fleet

BENCHMARK_MAIN();
