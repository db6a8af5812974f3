// VDA 5050 figures: the master control's cost per state message (parse + registry), the CPU of
// 100 vehicles' state traffic through one master-control process over a real broker, and the
// order's trip through the broker to the vehicle.

#include <benchmark/benchmark.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <mutex>
#include <thread>

#include "fleet/mqtt/client.hpp"
#include "fleet/sim/vda5050_link.hpp"
#include "fleet/vda5050/order.hpp"
#include "fleet/vda5050/state.hpp"
#include "fleet/vda5050/vehicle_registry.hpp"
#include "mosquitto_broker.hpp"

using namespace fleet;
using namespace std::chrono_literals;

namespace {

constexpr int kVehicles = 100;

std::string serial(int i) {
  return "V" + std::to_string(i);
}

/// A state as a moving vehicle sends it: 4 nodes and 3 edges ahead, 2 actions, position, velocity.
vda5050::State movingState(int vehicle, std::uint32_t header) {
  vda5050::State s;
  s.header = {header, vda5050::isoTimestamp(1'790'000'000'000'000'000), vda5050::kVersion, "acme",
              serial(vehicle)};
  s.orderId = "t1";
  s.orderUpdateId = 3;
  s.lastNodeId = "n10";
  s.lastNodeSequenceId = 6;
  s.driving = true;
  s.paused = false;
  s.newBaseRequest = false;
  s.distanceSinceLastNode = 0.4;
  for (int k = 0; k < 4; ++k) {
    s.nodeStates.push_back({"n" + std::to_string(11 + k), static_cast<std::uint32_t>(8 + 2 * k), k < 2,
                            vda5050::NodePosition{1.0 + k, 2.0, {}, {}, {}, "small"}});
    if (k > 0) {
      s.edgeStates.push_back({"e" + std::to_string(k), static_cast<std::uint32_t>(7 + 2 * k), k < 2});
    }
  }
  s.agvPosition = vda5050::AgvPosition{1.4, 2.0, 0.0, "small", true};
  s.velocity = vda5050::Velocity{0.8, 0.0, 0.0};
  s.actionStates = {{"t1-pick", std::string("pick"), "FINISHED", {}},
                    {"t1-drop", std::string("drop"), "WAITING", {}}};
  s.batteryState = {76.0, false};
  return s;
}

vda5050::VehicleRegistry registry() {
  std::vector<vda5050::VehicleEntry> v;
  for (int i = 0; i < kVehicles; ++i) {
    v.push_back({"acme", serial(i), "r" + std::to_string(i)});
  }
  return {"uagv", "small", v};
}

double processCpuS() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + static_cast<double>(ts.tv_nsec) * 1e-9;
}

// Parse, check and map one state message (no MQTT): the master control's work per message.
void BM_RegistryState(benchmark::State& st) {
  auto r = registry();
  const std::string topic = "uagv/v2/acme/V7/state";
  const std::string payload = vda5050::toJson(movingState(7, 1)).dump();
  for (auto _ : st) {
    auto out = r.onMessage(topic, payload);
    benchmark::DoNotOptimize(out);
  }
  st.counters["bytes"] = static_cast<double>(payload.size());
}
BENCHMARK(BM_RegistryState)->Unit(benchmark::kMicrosecond);

// 100 vehicles at 1 Hz plus one event each per second (200 states/s) from another process,
// through a real broker, into one master-control process (MQTT receive + parse + registry).
// CPU of that process over 10 s, as a share of one core.
void BM_HundredVehiclesStateTraffic(benchmark::State& st) {
  std::vector<test::BrokerVehicle> vehicles;
  for (int i = 0; i < kVehicles; ++i) {
    vehicles.push_back({"acme", serial(i), "pw" + std::to_string(i)});
  }
  test::MosquittoBroker broker(vehicles);
  constexpr double kSeconds = 10.0;
  for (auto _ : st) {
    auto r = registry();
    std::mutex mutex;
    std::atomic<std::uint64_t> received{0};
    mqtt::ClientOptions o;
    o.port = broker.port();
    o.client_id = "master";
    o.username = test::MosquittoBroker::kMasterUser;
    o.password = test::MosquittoBroker::kMasterPassword;
    auto master = mqtt::Client::start(o, [&](const std::string& t, const std::string& p) {
      std::lock_guard lock(mutex);
      (void)r.onMessage(t, p);
      received.fetch_add(1);
    });
    if (!master) {
      st.SkipWithError(master.error().message.c_str());
      return;
    }
    (*master)->subscribe("uagv/v2/+/+/state", 0);
    while (!(*master)->connected()) {
      std::this_thread::sleep_for(10ms);
    }
    std::this_thread::sleep_for(200ms);
    const pid_t child = fork();
    if (child == 0) {
      mqtt::ClientOptions po = o;
      po.client_id = "vehicles";
      auto pub = mqtt::Client::start(po, {});
      while (pub && !(*pub)->connected()) {
        std::this_thread::sleep_for(10ms);
      }
      std::vector<std::string> payloads;
      for (int i = 0; i < kVehicles; ++i) {
        payloads.push_back(vda5050::toJson(movingState(i, 1)).dump());
      }
      const auto start = std::chrono::steady_clock::now();
      const auto period = std::chrono::duration<double>(1.0 / (2.0 * kVehicles));
      for (int k = 0; k < static_cast<int>(2 * kVehicles * kSeconds); ++k) {
        std::this_thread::sleep_until(start +
                                      std::chrono::duration_cast<std::chrono::nanoseconds>(period * k));
        const int i = k % kVehicles;
        (*pub)->publish("uagv/v2/acme/" + serial(i) + "/state", payloads[static_cast<std::size_t>(i)], 0,
                        false);
      }
      std::this_thread::sleep_for(500ms);
      _exit(0);
    }
    const double cpu0 = processCpuS();
    const auto t0 = std::chrono::steady_clock::now();
    int status = 0;
    waitpid(child, &status, 0);
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const double cpu = processCpuS() - cpu0;
    st.counters["states_per_s"] = static_cast<double>(received.load()) / wall;
    st.counters["core_share_pct"] = 100.0 * cpu / wall;
    st.counters["received"] = static_cast<double>(received.load());
    st.counters["online"] =
        static_cast<double>(std::count_if(r.vehicles().begin(), r.vehicles().end(), [](const auto& v) {
          return v.second.health == vda5050::VehicleHealth::kOnline;
        }));
  }
}
BENCHMARK(BM_HundredVehiclesStateTraffic)->Iterations(1)->Unit(benchmark::kSecond)->UseRealTime();

// An order from the master control's publish to the vehicle's inbox, through the broker
// (the vehicle's simulator loop polls its inbox every 100 us here).
void BM_OrderThroughTheBroker(benchmark::State& st) {
  test::MosquittoBroker broker({{"acme", "V0", "pw0"}});
  sim::Vda5050LinkOptions lo;
  lo.port = broker.port();
  lo.manufacturer = "acme";
  lo.serial = "V0";
  lo.username = "acme-V0";
  lo.password = "pw0";
  auto link = sim::Vda5050Link::start(lo);
  mqtt::ClientOptions o;
  o.port = broker.port();
  o.client_id = "master";
  o.username = test::MosquittoBroker::kMasterUser;
  o.password = test::MosquittoBroker::kMasterPassword;
  auto master = mqtt::Client::start(o, {});
  if (!link || !master) {
    st.SkipWithError("no broker connection");
    return;
  }
  while (!(*link)->connected() || !(*master)->connected()) {
    std::this_thread::sleep_for(10ms);
  }
  std::this_thread::sleep_for(200ms);
  vda5050::Order order;
  order.header = {0, vda5050::isoTimestamp(0), vda5050::kVersion, "acme", "V0"};
  order.orderId = "t1";
  order.nodes = {{"n1", 0, true, vda5050::NodePosition{1.0, 2.0, {}, 0.2, {}, "small"}, {}},
                 {"n2", 2, true, vda5050::NodePosition{2.0, 2.0, {}, 0.2, {}, "small"}, {}}};
  order.edges = {{"n1-n2", 1, true, "n1", "n2", {}, {}, {}}};
  const std::string payload = vda5050::toJson(order).dump();
  std::vector<double> samples;
  for (auto _ : st) {
    const auto t0 = std::chrono::steady_clock::now();
    (*master)->publish("uagv/v2/acme/V0/order", payload, 0, false);
    while ((*link)->take(0).orders.empty()) {
      std::this_thread::sleep_for(100us);
    }
    const double ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    st.SetIterationTime(ms * 1e-3);
    samples.push_back(ms);
  }
  std::sort(samples.begin(), samples.end());
  st.counters["p50_ms"] = samples[samples.size() / 2];
  st.counters["p99_ms"] = samples[samples.size() * 99 / 100];
  st.counters["max_ms"] = samples.back();
}
BENCHMARK(BM_OrderThroughTheBroker)->Iterations(1000)->UseManualTime()->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
