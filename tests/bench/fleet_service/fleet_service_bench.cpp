// The fleet manager and WMS adapter as real processes, with 200 simulated robots online over DDS,
// on each task store in one run: durable SQLite (synchronous=FULL, WAL), then PostgreSQL 15 (a
// server of the bench's own on a Unix socket, fsync and synchronous commit on; the manager takes
// the lease as a lone active manager does):
//  - PostToAssignment: latency from the start of an HTTP POST of one task to the moment a robot
//    receives its TaskAssignment (robots finish tasks at once, so one is always idle);
//  - Intake: sustained HTTP intake with several clients posting batches (2xx = durably stored).

#include <benchmark/benchmark.h>
#include <httplib.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <thread>

#include "fleet/core/clock.hpp"
#include "fleet/transport/dds.hpp"
#include "postgres_server.hpp"
#include "test_process.hpp"

using namespace fleet;
using namespace std::chrono_literals;
using nlohmann::json;
using Clk = std::chrono::steady_clock;

namespace {

constexpr int kRobots = 200;

struct Fleet {
  /// `store`: "sqlite" or "postgresql".
  explicit Fleet(const std::string& store) : name(store) {
    domain = std::to_string(test::uniqueDomain());
    setenv("FLEET_DDS_DOMAIN", domain.c_str(), 1);
    dir = std::filesystem::temp_directory_path() / ("fleet_bench_" + domain);
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    json stations = json::array();
    for (int i = 0; i < 20; ++i) {
      stations.push_back(
          {{"name", "S-" + std::to_string(i)}, {"x", 2.0 * i}, {"y", 5.0}, {"kinds", {"pickup", "dropoff"}}});
    }
    std::ofstream(dir / "stations.json") << json{{"stations", stations}}.dump();
    json config = {{"stations", (dir / "stations.json").string()}, {"lease_s", 5.0}};
    if (store == "postgresql") {
      pg = std::make_unique<test::PostgresServer>(true);
      if (!pg->ok()) {
        error = "PostgreSQL: " + pg->error();
        return;
      }
      config["store"] = pg->url();
    } else {
      config["db"] = (dir / "fleet.db").string();
      config["sync"] = "full";
    }
    std::ofstream(dir / "manager.json") << config.dump();
    port = test::freePort();
    manager = std::make_unique<test::ChildProcess>(
        FLEET_BINARY_DIR "/services/fleet_manager/fleet_manager",
        std::vector<std::string>{"--config", (dir / "manager.json").string(), "--log-level", "warn"},
        std::vector<std::pair<std::string, std::string>>{{"FLEET_DDS_DOMAIN", domain}});
    adapter = std::make_unique<test::ChildProcess>(
        FLEET_BINARY_DIR "/services/wms_adapter/wms_adapter",
        std::vector<std::string>{"--stations", (dir / "stations.json").string(), "--port",
                                 std::to_string(port), "--log-level", "warn"},
        std::vector<std::pair<std::string, std::string>>{{"FLEET_DDS_DOMAIN", domain}});
    robots = std::thread([this] { runRobots(); });
    httplib::Client c("127.0.0.1", port);
    const auto end = Clk::now() + 30s;
    while (Clk::now() < end) {
      auto r = c.Get("/v1/health");
      if (r && r->status == 200) {
        break;
      }
      std::this_thread::sleep_for(50ms);
    }
    std::this_thread::sleep_for(1500ms);  // robots registered
  }
  ~Fleet() {
    stop = true;
    if (robots.joinable()) {
      robots.join();
    }
    adapter.reset();
    manager.reset();
    pg.reset();
    std::filesystem::remove_all(dir);
  }

  /// 200 robots: state at 5 Hz; every assignment is stamped on arrival and finished at once when
  /// `finish` is set.
  void runRobots() {
    transport::Participant p;
    transport::Writer<msg::RobotState> states(p);
    transport::Writer<msg::TaskStatus> statuses(p);
    transport::Reader<msg::TaskAssignment> orders(p);
    WallClock wall;
    auto lastStates = Clk::now() - 1s;
    // What each robot reports it carries: the manager requeues a task its robot does not report
    // for reconcile_s.
    std::map<std::string, std::string> carrying;
    while (!stop) {
      if (orders.waitForData(5ms)) {
        const auto now = Clk::now();
        for (const auto& a : orders.take()) {
          carrying[a.robot_id] = finish ? std::string() : a.task_id;
          if (a.task_id.empty()) {
            continue;
          }
          {
            std::lock_guard lock(m);
            received[a.task_id] = now;
          }
          if (finish) {
            for (auto st : {msg::TaskState::EnRoute, msg::TaskState::Done}) {
              statuses.write({a.robot_id, a.task_id, a.revision, st, 1.0f, "", wall.nowNs()});
            }
          }
        }
      }
      if (Clk::now() - lastStates > 200ms) {
        for (int i = 0; i < kRobots; ++i) {
          msg::RobotState s;
          s.robot_id = "r" + std::to_string(i);
          s.stamp_ns = wall.nowNs();
          s.pose = {0.2 * i, 0, 0};
          s.battery = 0.9f;
          s.task_id = carrying[s.robot_id];
          states.write(s);
        }
        lastStates = Clk::now();
      }
    }
  }

  std::string name;
  std::string error;  ///< why the fleet could not start (the benchmarks then fail with it)
  std::unique_ptr<test::PostgresServer> pg;
  std::string domain;
  std::filesystem::path dir;
  int port = 0;
  std::unique_ptr<test::ChildProcess> manager;
  std::unique_ptr<test::ChildProcess> adapter;
  std::thread robots;
  std::atomic<bool> stop{false};
  std::atomic<bool> finish{true};
  std::mutex m;
  std::map<std::string, Clk::time_point> received;
};

std::unique_ptr<Fleet> gFleet;
std::atomic<int> gNext{0};

/// The fleet on `store`, started on first use; the other store's fleet is stopped first (the
/// benchmarks of one store are registered together, so each fleet starts once).
Fleet* fleetOn(const std::string& store, benchmark::State& state) {
  if (!gFleet || gFleet->name != store) {
    gFleet.reset();
    gFleet = std::make_unique<Fleet>(store);
  }
  if (!gFleet->error.empty()) {
    state.SkipWithError(gFleet->error.c_str());
    return nullptr;
  }
  return gFleet.get();
}

void BM_PostToAssignment(benchmark::State& state, const std::string& store) {
  Fleet* fleet = fleetOn(store, state);
  if (fleet == nullptr) {
    return;
  }
  Fleet& f = *fleet;
  f.finish = true;
  httplib::Client c("127.0.0.1", f.port);
  std::vector<double> ms;
  for (auto _ : state) {
    const std::string id = "lat-" + std::to_string(gNext++);
    const auto t0 = Clk::now();
    auto r = c.Post("/v1/tasks", json{{"id", id}, {"kind", "goto"}, {"station", "S-3"}}.dump(),
                    "application/json");
    if (!r || r->status != 201) {
      state.SkipWithError("POST failed");
      break;
    }
    std::optional<Clk::time_point> got;
    const auto end = Clk::now() + 5s;
    while (!got && Clk::now() < end) {
      {
        std::lock_guard lock(f.m);
        auto it = f.received.find(id);
        if (it != f.received.end()) {
          got = it->second;
        }
      }
      if (!got) {
        std::this_thread::sleep_for(200us);
      }
    }
    if (!got) {
      state.SkipWithError("assignment never arrived");
      break;
    }
    ms.push_back(std::chrono::duration<double, std::milli>(*got - t0).count());
    std::this_thread::sleep_for(20ms);  // paced, so every task finds an idle robot
  }
  std::sort(ms.begin(), ms.end());
  if (!ms.empty()) {
    state.counters["p50_ms"] = ms[ms.size() / 2];
    state.counters["p99_ms"] = ms[static_cast<std::size_t>(0.99 * static_cast<double>(ms.size() - 1))];
    state.counters["max_ms"] = ms.back();
  }
}

void BM_Intake(benchmark::State& state, const std::string& store) {
  Fleet* fleet = fleetOn(store, state);
  if (fleet == nullptr) {
    return;
  }
  Fleet& f = *fleet;
  f.finish = false;
  const int clients = static_cast<int>(state.range(0));
  const int batch = static_cast<int>(state.range(1));
  std::int64_t stored = 0;
  double seconds = 0;
  for (auto _ : state) {
    std::atomic<std::int64_t> ok{0};
    std::atomic<std::int64_t> failed{0};
    const auto t0 = Clk::now();
    std::vector<std::thread> threads;
    for (int k = 0; k < clients; ++k) {
      threads.emplace_back([&] {
        httplib::Client c("127.0.0.1", f.port);
        c.set_read_timeout(30, 0);
        while (Clk::now() - t0 < 5s) {
          json tasks = json::array();
          for (int i = 0; i < batch; ++i) {
            tasks.push_back({{"id", "in-" + std::to_string(gNext++)}, {"kind", "goto"}, {"station", "S-1"}});
          }
          auto r = c.Post("/v1/tasks", tasks.dump(), "application/json");
          if (r && (r->status == 201 || r->status == 200)) {
            ok += batch;
          } else {
            failed += batch;
          }
        }
      });
    }
    for (auto& t : threads) {
      t.join();
    }
    seconds += std::chrono::duration<double>(Clk::now() - t0).count();
    stored += ok;
    state.counters["failed"] = static_cast<double>(failed.load());
  }
  state.counters["tasks_per_s"] = static_cast<double>(stored) / seconds;
}

BENCHMARK_CAPTURE(BM_PostToAssignment, sqlite, std::string("sqlite"))
    ->Iterations(500)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK_CAPTURE(BM_Intake, sqlite, std::string("sqlite"))
    ->Args({4, 50})
    ->Args({8, 100})
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK_CAPTURE(BM_PostToAssignment, postgresql, std::string("postgresql"))
    ->Iterations(500)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK_CAPTURE(BM_Intake, postgresql, std::string("postgresql"))
    ->Args({4, 50})
    ->Args({8, 100})
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  gFleet.reset();
  return 0;
}
