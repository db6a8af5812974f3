// Every service as a process: /metrics (process_* included) passes `promtool check metrics`,
// /livez and /readyz answer truthfully, a real Prometheus on loopback scrapes a running lockstep
// fleet, answers a query and evaluates the shipped alert rules without error. A taken metrics
// port, a bad option and a bad log level exit 2; --version exits 0; JSON logs are one object per
// line.

#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <httplib.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "fleet_stack.hpp"
#include "mosquitto_broker.hpp"
#include "test_process.hpp"

using namespace std::chrono_literals;
namespace fs = std::filesystem;

namespace {

const std::string kBin = FLEET_BINARY_DIR;
const std::string kScenario = FLEET_SOURCE_DIR "/sim/scenarios/one_robot.json";
const std::string kSite = FLEET_SOURCE_DIR "/sim/scenarios/small_warehouse_12_parking.site.json";

/// A loopback port free right now (bound to 0, read back, released).
using fleet::test::freePort;

struct Ran {
  int code = -1;
  std::string out;  // stdout and stderr
};
/// Runs a shell command line to its end (bounded by `timeout` in seconds).
Ran run(const std::string& cmd, int timeoutS = 30) {
  Ran r;
  FILE* p = popen(("timeout " + std::to_string(timeoutS) + " " + cmd + " 2>&1").c_str(), "r");
  char buf[4096];
  while (std::fgets(buf, sizeof(buf), p) != nullptr) {
    r.out += buf;
  }
  const int st = pclose(p);
  r.code = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
  return r;
}

std::optional<httplib::Result> get(int port, const std::string& path) {
  httplib::Client c("127.0.0.1", port);
  c.set_connection_timeout(1s);
  c.set_read_timeout(5s);
  auto r = c.Get(path);
  if (!r) {
    return std::nullopt;
  }
  return r;
}

/// Waits until GET path answers `status` (at most `within`).
bool waitFor(int port, const std::string& path, int status, std::chrono::seconds within) {
  const auto end = std::chrono::steady_clock::now() + within;
  while (std::chrono::steady_clock::now() < end) {
    if (auto r = get(port, path); r && (*r)->status == status) {
      return true;
    }
    std::this_thread::sleep_for(200ms);
  }
  return false;
}

/// The seven services of a small lockstep fleet (one robot, and a VDA 5050 bridge), each with its ops port.
class Fleet {
 public:
  Fleet() {
    domain_ = std::to_string(fleet::test::uniqueDomain());
    dir_ = fs::temp_directory_path() / ("fleet-ops-" + domain_);
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    std::ofstream(dir_ / "manager.json") << nlohmann::json{
        {"db", (dir_ / "fleet.db").string()},
        {"stations", kScenario},
        {"clock", "sim"}}.dump();
    std::ofstream(dir_ / "risk_map.json")
        << nlohmann::json{{"clock", "sim"}, {"lockstep", true}, {"rate_hz", 2}, {"site", kSite}}.dump();
    // The agent drives what the traffic manager releases; both are lockstep participants, as the
    // risk map is.
    std::ofstream(dir_ / "traffic.json")
        << nlohmann::json{{"site", kSite}, {"clock", "sim"}, {"lockstep", true}}.dump();
    const std::vector<std::pair<std::string, std::string>> env = {{"FLEET_DDS_DOMAIN", domain_}};
    auto start = [&](const std::string& name, const std::string& exe, std::vector<std::string> args) {
      ports[name] = freePort();
      args.insert(args.end(), {"--metrics-port", std::to_string(ports[name]), "--log-level", "warn"});
      procs_.push_back(std::make_unique<fleet::test::ChildProcess>(kBin + exe, args, env));
    };
    start("fleet_manager", "/services/fleet_manager/fleet_manager",
          {"--config", (dir_ / "manager.json").string()});
    start("wms_adapter", "/services/wms_adapter/wms_adapter",
          {"--stations", kScenario, "--port", std::to_string(freePort())});
    start("risk_map", "/services/risk_map/risk_map", {"--config", (dir_ / "risk_map.json").string()});
    start("traffic_manager", "/services/traffic_manager/traffic_manager",
          {"--config", (dir_ / "traffic.json").string()});
    start("robot_agent", "/services/robot_agent/robot_agent",
          {"--scenario", kScenario, "--clock", "lockstep"});
    start("fleet_sim", "/sim/src/fleet-sim",
          {"--scenario", kScenario, "--clock", "lockstep", "--participants", "3", "--duration", "600",
           "--max-speed", "5"});
    // The VDA 5050 bridge on a broker of this fleet's own, for a vehicle that never comes: it is
    // ready once it hears the broker, and its metrics are scraped like the others'.
    broker_ = std::make_unique<fleet::test::MosquittoBroker>(
        std::vector<fleet::test::BrokerVehicle>{{"fleet-sim", "v1", "pw-v1"}});
    std::ofstream(dir_ / "bridge.json")
        << nlohmann::json{{"broker",
                           {{"port", broker_->port()},
                            {"username", fleet::test::MosquittoBroker::kMasterUser},
                            {"password", fleet::test::MosquittoBroker::kMasterPassword}}},
                          {"map_id", "small_warehouse"},
                          {"vehicles", {{{"manufacturer", "fleet-sim"}, {"serial", "v1"}, {"robot", "v1"}}}}}
               .dump();
    start("vda5050_bridge", "/services/vda5050_bridge/vda5050_bridge",
          {"--config", (dir_ / "bridge.json").string()});
  }
  ~Fleet() { fs::remove_all(dir_); }

  std::map<std::string, int> ports;
  const fs::path& dir() const { return dir_; }

 private:
  std::string domain_;
  fs::path dir_;
  std::unique_ptr<fleet::test::MosquittoBroker> broker_;  // outlives the bridge (procs_ go first)
  std::vector<std::unique_ptr<fleet::test::ChildProcess>> procs_;
};

class OpsFleet : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { fleet_ = std::make_unique<Fleet>(); }
  static void TearDownTestSuite() { fleet_.reset(); }
  static std::unique_ptr<Fleet> fleet_;
};
std::unique_ptr<Fleet> OpsFleet::fleet_;

}  // namespace

TEST_F(OpsFleet, EveryServiceIsLiveThenReadyAndItsMetricsPassPromtool) {
  ASSERT_EQ(fleet_->ports.size(), 7u);
  for (const auto& [name, port] : fleet_->ports) {
    ASSERT_TRUE(waitFor(port, "/livez", 200, 30s)) << name << " never live";
    EXPECT_TRUE(waitFor(port, "/readyz", 200, 60s))
        << name << " never ready: " << (*get(port, "/readyz"))->body;
    auto m = get(port, "/metrics");
    ASSERT_TRUE(m) << name;
    EXPECT_EQ((*m)->get_header_value("Content-Type"), "text/plain; version=0.0.4; charset=utf-8");
    EXPECT_NE((*m)->body.find("fleet_build_info{service=\"" + name + "\""), std::string::npos) << name;
    EXPECT_NE((*m)->body.find(name + "_rejected_samples_total"), std::string::npos) << name;
    for (const char* process : {"\nprocess_cpu_seconds_total ", "\nprocess_resident_memory_bytes ",
                                "\nprocess_open_fds ", "\nprocess_start_time_seconds "}) {
      EXPECT_NE((*m)->body.find(process), std::string::npos) << name << " lacks" << process;
    }
    const auto file = fleet_->dir() / (name + ".prom");
    std::ofstream(file) << (*m)->body;
    const auto check = run("promtool check metrics < " + file.string());
    EXPECT_EQ(check.code, 0) << name << ": " << check.out;
  }
}

TEST_F(OpsFleet, FleetProbeAsTheContainersUseIt) {
  const std::string probe = kBin + "/services/fleet_probe/fleet-probe";
  const int port = fleet_->ports.at("fleet_manager");
  ASSERT_TRUE(waitFor(port, "/livez", 200, 30s));
  EXPECT_EQ(run("env FLEET_METRICS_PORT=" + std::to_string(port) + " " + probe + " /livez").code, 0);
  EXPECT_EQ(run(probe + " " + std::to_string(port) + " /livez").code, 0);
  EXPECT_EQ(run(probe + " " + std::to_string(port) + " /no-such-page").code, 1);
  EXPECT_EQ(run(probe + " " + std::to_string(freePort()) + " /livez").code, 1);  // nobody listens
  EXPECT_EQ(run("env -u FLEET_METRICS_PORT " + probe + " /livez").code, 2);
  EXPECT_EQ(run(probe + " 80x80 /livez").code, 2);
}

TEST_F(OpsFleet, AFloodOfProbesIsAnsweredAndTheServiceStaysLive) {
  // 4 clients x 500 probes as fast as they go (a misconfigured prober): every one answered, and the
  // manager still scrapes and turns afterwards.
  const int port = fleet_->ports.at("fleet_manager");
  ASSERT_TRUE(waitFor(port, "/readyz", 200, 30s));
  std::atomic<int> ok{0};
  std::vector<std::thread> clients;
  for (int k = 0; k < 4; ++k) {
    clients.emplace_back([&] {
      httplib::Client c("127.0.0.1", port);
      c.set_keep_alive(true);
      c.set_read_timeout(10s);
      for (int i = 0; i < 500; ++i) {
        if (auto r = c.Get(i % 2 == 0 ? "/livez" : "/readyz"); r && r->status == 200) {
          ++ok;
        }
      }
    });
  }
  for (auto& t : clients) {
    t.join();
  }
  EXPECT_EQ(ok.load(), 2000);
  EXPECT_TRUE(waitFor(port, "/livez", 200, 5s));
  auto m = get(port, "/metrics");
  ASSERT_TRUE(m);
  EXPECT_EQ((*m)->status, 200);
}

TEST(OpsBadInput, ATaskDatabaseThatCannotBeOpenedIsOneLineAndExitTwo) {
  // /proc refuses new files even to root: the database cannot be created there.
  const auto r = run(kBin + "/services/fleet_manager/fleet_manager --db /proc/fleet-ops-test.db --stations " +
                     kScenario + " --log-format json");
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("cannot open task store /proc/fleet-ops-test.db"), std::string::npos) << r.out;
  // A site that is not a site: one line naming the file, exit 2, before any port or DDS is opened.
  const auto dir = fs::temp_directory_path() / ("fleet-ops-badsite-" + std::to_string(getpid()));
  fs::create_directories(dir);
  std::ofstream(dir / "site.json") << "{\"format\": \"fleet-site/1\", \"name\": ";
  const auto s = run(kBin + "/services/risk_map/risk_map --config /dev/null");
  const auto t =
      run(kBin + "/services/traffic_manager/traffic_manager --site " + (dir / "site.json").string());
  fs::remove_all(dir);
  EXPECT_EQ(t.code, 2) << t.out;
  EXPECT_NE(t.out.find("site.json"), std::string::npos) << t.out;
  EXPECT_EQ(s.code, 2) << s.out;
}

TEST_F(OpsFleet, ThePortOfARunningServiceIsRefusedToASecondOneWithExitTwo) {
  const int taken = fleet_->ports.at("fleet_manager");
  // The fleet starts with the suite: until the manager listens the port is free, and the second
  // service would take it (and the manager exit 2 instead).
  ASSERT_TRUE(waitFor(taken, "/livez", 200, 30s)) << "the fleet manager never listened on " << taken;
  const auto r = run(kBin + "/services/risk_map/risk_map --metrics-port " + std::to_string(taken));
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("cannot listen on 127.0.0.1:" + std::to_string(taken)), std::string::npos) << r.out;
}

TEST_F(OpsFleet, ARealPrometheusScrapesEveryServiceAndAnswersAQuery) {
  ASSERT_TRUE(fs::exists("/usr/bin/prometheus")) << "prometheus is not installed (scripts/setup installs it)";
  const int promPort = freePort();
  std::string targets;
  for (const auto& [name, port] : fleet_->ports) {
    targets += "  - job_name: " + name +
               "\n    static_configs:\n      - targets: ['127.0.0.1:" + std::to_string(port) + "']\n";
  }
  const auto cfg = fleet_->dir() / "prometheus.yml";
  // The shipped alert rules too, evaluated every second.
  std::ofstream(cfg) << "global:\n  scrape_interval: 1s\n  scrape_timeout: 1s\n  evaluation_interval: 1s\n"
                     << "rule_files:\n  - " FLEET_SOURCE_DIR "/deploy/prometheus/fleet-alerts.yml\n"
                     << "scrape_configs:\n"
                     << targets;
  fleet::test::ChildProcess prom(
      "/usr/bin/prometheus",
      {"--config.file=" + cfg.string(), "--storage.tsdb.path=" + (fleet_->dir() / "tsdb").string(),
       "--web.listen-address=127.0.0.1:" + std::to_string(promPort), "--log.level=warn"});
  httplib::Client c("127.0.0.1", promPort);
  c.set_read_timeout(5s);
  auto query = [&](const std::string& q) -> nlohmann::json {
    auto r = c.Get("/api/v1/query", httplib::Params{{"query", q}}, httplib::Headers{});
    if (!r || r->status != 200) {
      return nullptr;
    }
    return nlohmann::json::parse(r->body, nullptr, false);
  };
  // Every target up, and the robot agent's control cycles counted (the fleet is running).
  const auto end = std::chrono::steady_clock::now() + 90s;
  nlohmann::json up;
  nlohmann::json cycles;
  while (std::chrono::steady_clock::now() < end) {
    up = query("count(up == 1)");
    cycles = query("sum(robot_agent_cycles_total)");
    if (up.is_object() && !up["data"]["result"].empty() && up["data"]["result"][0]["value"][1] == "7" &&
        cycles.is_object() && !cycles["data"]["result"].empty() &&
        std::stod(cycles["data"]["result"][0]["value"][1].get<std::string>()) > 0) {
      break;
    }
    std::this_thread::sleep_for(500ms);
  }
  ASSERT_TRUE(up.is_object()) << "Prometheus never answered on port " << promPort;
  ASSERT_FALSE(up["data"]["result"].empty()) << up.dump();
  EXPECT_EQ(up["data"]["result"][0]["value"][1], "7") << up.dump();
  ASSERT_FALSE(cycles["data"]["result"].empty()) << cycles.dump();
  EXPECT_GT(std::stod(cycles["data"]["result"][0]["value"][1].get<std::string>()), 0.0);
  // A histogram query as a dashboard makes it.
  const auto p99 =
      query("histogram_quantile(0.99, sum by (le) (rate(robot_agent_cycle_seconds_bucket[1m])))");
  ASSERT_TRUE(p99.is_object());
  EXPECT_EQ(p99["status"], "success") << p99.dump();
  // Every query of the shipped Grafana dashboard is valid PromQL and finds series in a running fleet
  // (a renamed metric would leave its panel empty).
  std::ifstream dashFile(FLEET_SOURCE_DIR "/deploy/grafana-dashboard.json");
  const auto dash = nlohmann::json::parse(dashFile);
  int queries = 0;
  for (const auto& panel : dash["panels"]) {
    for (const auto& t : panel["targets"]) {
      const std::string expr = t["expr"];
      auto r = query(expr);
      ASSERT_TRUE(r.is_object()) << expr;
      EXPECT_EQ(r["status"], "success") << expr << ": " << r.dump();
      // rate() over 5 m may still be empty this early; the series themselves must exist.
      if (expr.find("rate(") == std::string::npos) {
        EXPECT_FALSE(r["data"]["result"].empty()) << panel["title"] << ": " << expr;
      }
      ++queries;
    }
  }
  EXPECT_GE(queries, 12);
  // Every alert rule of deploy/prometheus/fleet-alerts.yml loaded and evaluated on the running fleet
  // without an error (a rule that fails to evaluate never fires), and FleetServiceDown not pending.
  auto text = [](const nlohmann::json& rule, const char* key) {
    const auto it = rule.find(key);
    return it != rule.end() && it->is_string() ? *it->get_ptr<const std::string*>() : std::string();
  };
  nlohmann::json rules;
  for (const auto stop = std::chrono::steady_clock::now() + 20s; std::chrono::steady_clock::now() < stop;
       std::this_thread::sleep_for(500ms)) {
    auto r = c.Get("/api/v1/rules");
    rules = r && r->status == 200 ? nlohmann::json::parse(r->body, nullptr, false) : nullptr;
    int evaluated = 0;
    if (rules.is_object() && rules["data"]["groups"].is_array()) {
      for (const auto& g : rules["data"]["groups"]) {
        for (const auto& rule : g["rules"]) {
          evaluated += text(rule, "health") != "unknown" ? 1 : 0;
        }
      }
    }
    if (evaluated >= 10) {
      break;
    }
  }
  ASSERT_TRUE(rules.is_object()) << "no /api/v1/rules";
  int loaded = 0;
  for (const auto& g : rules["data"]["groups"]) {
    for (const auto& rule : g["rules"]) {
      ++loaded;
      EXPECT_EQ(text(rule, "health"), "ok") << rule.dump();
      if (text(rule, "name") == "FleetServiceDown") {
        EXPECT_EQ(text(rule, "state"), "inactive") << rule.dump();
      }
    }
  }
  EXPECT_GE(loaded, 10) << rules.dump();
}

TEST(OpsCommandLine, EveryBinaryHasVersionAndExitsTwoOnBadUsage) {
  const std::vector<std::string> bins = {"/services/fleet_manager/fleet_manager",
                                         "/services/wms_adapter/wms_adapter",
                                         "/services/risk_map/risk_map",
                                         "/services/robot_agent/robot_agent",
                                         "/services/traffic_manager/traffic_manager",
                                         "/services/vda5050_bridge/vda5050_bridge",
                                         "/sim/src/fleet-sim",
                                         "/services/fleetctl/fleetctl",
                                         "/services/risk_render/risk_render",
                                         "/services/fleet_probe/fleet-probe"};
  for (const auto& b : bins) {
    const auto v = run(kBin + b + " --version");
    EXPECT_EQ(v.code, 0) << b << ": " << v.out;
    EXPECT_NE(v.out.find(FLEET_TEST_VERSION), std::string::npos) << b << ": " << v.out;
    const auto bad = run(kBin + b + " --no-such-option");
    EXPECT_EQ(bad.code, 2) << b << ": " << bad.out;
  }
  // A bad log level is bad configuration (it was 1, a run-time failure).
  for (const auto& b : {"/services/fleet_manager/fleet_manager", "/services/risk_map/risk_map",
                        "/services/traffic_manager/traffic_manager", "/services/wms_adapter/wms_adapter",
                        "/services/robot_agent/robot_agent"}) {
    const auto r = run(kBin + b + " --log-level verbose");
    EXPECT_EQ(r.code, 2) << b << ": " << r.out;
    EXPECT_NE(r.out.find("unknown log level"), std::string::npos) << b << ": " << r.out;
    const auto f = run(kBin + b + " --log-format xml");
    EXPECT_EQ(f.code, 2) << b << ": " << f.out;
  }
  const auto sim = run(kBin + "/sim/src/fleet-sim --scenario " + kScenario + " --log-level verbose");
  EXPECT_EQ(sim.code, 2) << sim.out;
}

TEST(OpsCommandLine, TheBridgesTuningIsConfigurableAndOutOfRangeValuesAreRefusedByName) {
  const auto dir = fs::temp_directory_path() / ("fleet-ops-bridge-" + std::to_string(getpid()));
  fs::create_directories(dir);
  auto config = [&](const std::string& tuning, int timeoutS = 10) {
    std::ofstream(dir / "bridge.json")
        << R"({"broker": {"port": 1, "username": "m", "password": "p"}, "map_id": "m", )" << tuning
        << R"("vehicles": [{"manufacturer": "a", "serial": "s", "robot": "r1"}]})";
    // A domain of its own: an accepted configuration starts the bridge's DDS participant.
    return run("env FLEET_DDS_DOMAIN=" + std::to_string(fleet::test::uniqueDomain()) + " " + kBin +
                   "/services/vda5050_bridge/vda5050_bridge --config " + (dir / "bridge.json").string(),
               timeoutS);
  };
  const auto bad = config(R"("field_cancel_s": -1, "order_retries": 1000, )");
  const auto typo = config(R"("field_cancel": 3, )");
  // Accepted: the bridge starts (and keeps trying the broker, which is not there, until stopped).
  const auto good = config(R"("field_cancel_s": 5.5, "order_retries": 7, "order_ack_timeout_s": 4, )", 3);
  fs::remove_all(dir);
  EXPECT_EQ(good.code, 124) << good.out;
  EXPECT_NE(good.out.find("re-sent 7 times"), std::string::npos) << good.out;
  EXPECT_NE(good.out.find("unanswered after 4 s"), std::string::npos) << good.out;
  EXPECT_NE(good.out.find("cancelled after 5.5 s"), std::string::npos) << good.out;
  EXPECT_EQ(bad.code, 2) << bad.out;
  EXPECT_NE(bad.out.find("field_cancel_s"), std::string::npos) << bad.out;
  EXPECT_NE(bad.out.find("order_retries"), std::string::npos) << bad.out;
  EXPECT_EQ(typo.code, 2) << typo.out;
  EXPECT_NE(typo.out.find("field_cancel"), std::string::npos) << typo.out;
}

TEST(OpsLogs, JsonFormatIsOneObjectPerLineWithTimeLevelAndService) {
  // A configuration error logged as JSON: the multi-line problem list stays on one line.
  const auto r =
      run(kBin + "/services/fleet_manager/fleet_manager --log-format json --stations /nonexistent.json");
  EXPECT_EQ(r.code, 2) << r.out;
  std::istringstream lines(r.out);
  int n = 0;
  for (std::string line; std::getline(lines, line);) {
    const auto j = nlohmann::json::parse(line, nullptr, false);
    ASSERT_TRUE(j.is_object()) << "not JSON: " << line;
    EXPECT_TRUE(j.contains("time") && j.contains("level") && j.contains("msg")) << line;
    EXPECT_EQ(j["service"], "fleet_manager") << line;
    ++n;
  }
  EXPECT_GE(n, 1);
}

TEST(OpsProbes, AnAdapterWithoutManagerIsLiveNotReadyAndLogsEveryRequest) {
  // A fresh domain: no fleet manager answers. With a token set, /v1/health still answers without it.
  const std::string domain = std::to_string(fleet::test::uniqueDomain());
  const auto dir = fs::temp_directory_path() / ("fleet-ops-adapter-" + domain);
  fs::create_directories(dir);
  const int api = freePort();
  const int ops = freePort();
  std::ofstream(dir / "token") << "s3cret\n";
  std::ofstream(dir / "adapter.json")
      << nlohmann::json{{"stations", kScenario},
                        {"http", {{"port", api}, {"token_file", (dir / "token").string()}}}}
             .dump();
  fleet::test::ChildProcess adapter(
      "/bin/sh",
      {"-c", "exec " + kBin + "/services/wms_adapter/wms_adapter --config " +
                 (dir / "adapter.json").string() + " --metrics-port " + std::to_string(ops) +
                 " --log-format json 2> " + (dir / "log").string()},
      {{"FLEET_DDS_DOMAIN", domain}});
  ASSERT_TRUE(waitFor(ops, "/livez", 200, 30s));
  auto ready = get(ops, "/readyz");
  ASSERT_TRUE(ready);
  EXPECT_EQ((*ready)->status, 503);
  EXPECT_EQ((*ready)->body, "not ready: fleet_manager\n");
  auto health = get(api, "/v1/health");
  ASSERT_TRUE(health);
  EXPECT_EQ((*health)->status, 503);  // the manager is unreachable; not 401 for lack of a token
  EXPECT_EQ((*health)->body.find("s3cret"), std::string::npos);
  EXPECT_EQ((*get(api, "/v1/tasks"))->status, 401);
  auto m = get(ops, "/metrics");
  ASSERT_TRUE(m);
  EXPECT_NE((*m)->body.find("wms_adapter_http_responses_total{code=\"401\"} 1"), std::string::npos)
      << (*m)->body;
  EXPECT_NE((*m)->body.find("wms_adapter_http_responses_total{code=\"503\"} 1"), std::string::npos)
      << (*m)->body;
  adapter.kill(SIGTERM);
  EXPECT_EQ(adapter.wait(10s), 0);
  std::ifstream log(dir / "log");
  int access = 0;
  for (std::string line; std::getline(log, line);) {
    const auto j = nlohmann::json::parse(line, nullptr, false);
    ASSERT_TRUE(j.is_object()) << "not JSON: " << line;
    EXPECT_EQ(j["service"], "wms_adapter");
    const std::string msg = j["msg"];
    if (msg.rfind("access ", 0) == 0) {
      ++access;
      EXPECT_EQ(msg.find("s3cret"), std::string::npos) << msg;  // never the Authorization header
    }
  }
  EXPECT_EQ(access, 2);
  fs::remove_all(dir);
}

TEST(OpsProbes, SamplesTheAdapterRefusesAreCountedInItsMetrics) {
  // A TaskEvent whose task id is not an id (the edge checks): refused, and counted where
  // an operations stack looks, as every other service's refusals are.
  const std::string domain = std::to_string(fleet::test::uniqueDomain());
  const auto dir = fs::temp_directory_path() / ("fleet-ops-refused-" + domain);
  fs::create_directories(dir);
  const int api = freePort();
  const int ops = freePort();
  std::ofstream(dir / "adapter.json")
      << nlohmann::json{{"stations", kScenario}, {"http", {{"port", api}}}}.dump();
  fleet::test::ChildProcess adapter(kBin + "/services/wms_adapter/wms_adapter",
                                    {"--config", (dir / "adapter.json").string(), "--metrics-port",
                                     std::to_string(ops), "--log-level", "warn"},
                                    {{"FLEET_DDS_DOMAIN", domain}});
  ASSERT_TRUE(waitFor(ops, "/livez", 200, 30s));
  setenv("FLEET_DDS_DOMAIN", domain.c_str(), 1);
  fleet::transport::Participant p;
  fleet::transport::Writer<fleet::msg::TaskEvent> events(p);
  fleet::msg::TaskEvent bad;
  bad.task_id = "not an id!";
  bad.state = fleet::msg::TaskState::Done;
  // (The reason label is the topic, as for every service: ServiceOps keeps label values few.)
  const std::string counted = "wms_adapter_rejected_samples_total{reason=\"TaskEvent\"}";
  std::string body;
  for (int k = 0; k < 100 && body.find(counted) == std::string::npos; ++k) {
    events.write(bad);
    std::this_thread::sleep_for(200ms);
    if (auto m = get(ops, "/metrics"); m && *m) {
      body = (*m)->body;
    }
  }
  EXPECT_NE(body.find(counted), std::string::npos) << body;
  adapter.kill(SIGTERM);
  EXPECT_EQ(adapter.wait(10s), 0);
  fs::remove_all(dir);
}

TEST(OpsProbes, ARobotAgentWithoutSensorsIsLiveNotReady) {
  const std::string domain = std::to_string(fleet::test::uniqueDomain());
  const int ops = freePort();
  fleet::test::ChildProcess agent(
      kBin + "/services/robot_agent/robot_agent",
      {"--scenario", kScenario, "--metrics-port", std::to_string(ops), "--log-level", "warn"},
      {{"FLEET_DDS_DOMAIN", domain}});
  ASSERT_TRUE(waitFor(ops, "/livez", 200, 30s));
  // Give the once-a-second readiness update a turn, then: nothing publishes SensorFrame here.
  std::this_thread::sleep_for(1500ms);
  auto ready = get(ops, "/readyz");
  ASSERT_TRUE(ready);
  EXPECT_EQ((*ready)->status, 503);
  EXPECT_EQ((*ready)->body, "not ready: sensors\n");
  EXPECT_EQ((*get(ops, "/livez"))->status, 200);  // still live: its loop turns without sensors
}

TEST(OpsFleetctl, SpeaksHttpsToAServerItsCaSigned) {
  // A self-signed certificate for 127.0.0.1 and an https server answering /v1/health; fleetctl
  // trusts it with --ca-cert, and refuses it without (the system CAs did not sign it).
  const auto dir = fs::temp_directory_path() / ("fleet-ops-tls-" + std::to_string(getpid()));
  fs::create_directories(dir);
  const auto key = (dir / "key.pem").string();
  const auto cert = (dir / "cert.pem").string();
  const auto made =
      run("openssl req -x509 -newkey rsa:2048 -nodes -days 1 -subj /CN=127.0.0.1 -addext "
          "subjectAltName=IP:127.0.0.1 -keyout " +
          key + " -out " + cert);
  ASSERT_EQ(made.code, 0) << made.out;
  httplib::SSLServer server(cert.c_str(), key.c_str());
  ASSERT_TRUE(server.is_valid());
  server.Get("/v1/health", [](const httplib::Request&, httplib::Response& res) {
    res.set_content(R"({"status":"ok"})", "application/json");
  });
  const int port = server.bind_to_any_port("127.0.0.1");
  std::thread t([&] { server.listen_after_bind(); });
  const std::string url = " --url https://127.0.0.1:" + std::to_string(port);
  const auto ok = run(kBin + "/services/fleetctl/fleetctl" + url + " --ca-cert " + cert + " health");
  const auto untrusted = run(kBin + "/services/fleetctl/fleetctl" + url + " health");
  const auto plain =
      run(kBin + "/services/fleetctl/fleetctl --url http://127.0.0.1:1 --ca-cert " + cert + " health");
  server.stop();
  t.join();
  fs::remove_all(dir);
  EXPECT_EQ(ok.code, 0) << ok.out;
  EXPECT_NE(ok.out.find("\"ok\""), std::string::npos) << ok.out;
  EXPECT_EQ(untrusted.code, 1) << untrusted.out;
  EXPECT_EQ(plain.code, 2) << plain.out;
}

TEST(OpsBackup, AnOnlineBackupOfTheTaskDatabaseRestoresItsTasks) {
  // The procedure of docs/operator-guide.md: `sqlite3 DB ".backup FILE"` while the manager runs (the
  // online backup API: a consistent copy under WAL), then a manager started on the copy has the
  // tasks (no robots here, so they stay queued).
  const std::string domain = std::to_string(fleet::test::uniqueDomain());
  setenv("FLEET_DDS_DOMAIN", domain.c_str(), 1);
  const auto dir = fs::temp_directory_path() / ("fleet-ops-backup-" + domain);
  fs::remove_all(dir);
  fs::create_directories(dir);
  auto config = [&](const std::string& db) {
    const auto path = dir / (db + ".json");
    std::ofstream(path) << nlohmann::json{{"db", (dir / db).string()}, {"stations", kScenario}}.dump();
    return path.string();
  };
  const std::vector<std::pair<std::string, std::string>> env = {{"FLEET_DDS_DOMAIN", domain}};
  const int ops1 = freePort();
  auto manager = std::make_unique<fleet::test::ChildProcess>(
      kBin + "/services/fleet_manager/fleet_manager",
      std::vector<std::string>{"--config", config("fleet.db"), "--metrics-port", std::to_string(ops1),
                               "--log-level", "warn"},
      env);
  ASSERT_TRUE(waitFor(ops1, "/readyz", 200, 30s));
  {
    fleet::test::TaskClient client;
    for (const char* id : {"b-1", "b-2", "b-3"}) {
      auto ack = client.submit(fleet::test::transportTask(id, "P-1", "D-1"), 30s);
      ASSERT_TRUE(ack) << id;
      ASSERT_EQ(ack->result, fleet::msg::AckResult::Stored) << id << ": " << ack->detail;
    }
  }
  const auto backup =
      run("sqlite3 " + (dir / "fleet.db").string() + " \".backup '" + (dir / "backup.db").string() + "'\"");
  ASSERT_EQ(backup.code, 0) << backup.out;
  manager->kill(SIGTERM);
  EXPECT_EQ(manager->wait(10s), 0);
  manager.reset();

  const int ops2 = freePort();
  fleet::test::ChildProcess restored(
      kBin + "/services/fleet_manager/fleet_manager",
      {"--config", config("backup.db"), "--metrics-port", std::to_string(ops2), "--log-level", "warn"}, env);
  ASSERT_TRUE(waitFor(ops2, "/readyz", 200, 30s));
  std::string body;
  const auto end = std::chrono::steady_clock::now() + 10s;
  while (std::chrono::steady_clock::now() < end) {
    body = (*get(ops2, "/metrics"))->body;
    if (body.find("fleet_manager_tasks{state=\"queued\"} 3\n") != std::string::npos) {
      break;
    }
    std::this_thread::sleep_for(200ms);
  }
  EXPECT_NE(body.find("fleet_manager_tasks{state=\"queued\"} 3\n"), std::string::npos) << body;
  fs::remove_all(dir);
}
