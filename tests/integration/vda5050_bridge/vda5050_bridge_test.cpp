// The bridge as a process between DDS and a real broker, with fleet-sim running r1 as a VDA 5050
// vehicle and this test as the fleet manager and the traffic manager: a transport task (pick at
// the end of the band, drop on the way back) is released in pieces; the vehicle must drive the
// orders and updates the bridge makes of them, report every node, and the task must go Assigned,
// EnRoute, Loading, Delivering, Unloading, Done. Before it, bad input on the broker (a state that
// fails the checks, an unknown serial, another map) must fault r1 only until its next good state
// and never stop the bridge; after it, a broker restart must be survived; then the vehicle is
// killed: its last will must take it out of traffic control (TrafficProgress follows=false) and
// stop its RobotState. Throughout, the bridge's ops port tells the truth: live, ready only while it
// hears the broker, and metrics (promtool-clean) that count what happened.

#include <gtest/gtest.h>
#include <httplib.h>
#include <signal.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>

#include "fleet/mqtt/client.hpp"
#include "fleet/transport/dds.hpp"
#include "mosquitto_broker.hpp"
#include "test_process.hpp"

using namespace fleet;
using namespace std::chrono_literals;

namespace {

msg::TrafficRelease release(std::uint32_t seq, const std::vector<std::pair<int, double>>& base,
                            bool at_goal) {
  msg::TrafficRelease r;
  r.robot_id = "r1";
  r.epoch = 7;
  r.seq = seq;
  for (const auto& [node, x] : base) {
    r.base.push_back({node, x, node == 1000 ? 1.25 : 1.75});
  }
  r.ends_at_goal = at_goal;
  return r;
}

int status(int port, const std::string& path, std::string* body = nullptr) {
  httplib::Client c("127.0.0.1", port);
  c.set_connection_timeout(1s);
  c.set_read_timeout(5s);
  auto r = c.Get(path);
  if (!r) {
    return -1;
  }
  if (body != nullptr) {
    *body = r->body;
  }
  return r->status;
}

/// The value of one sample (`name{labels}` as exposed) in a Prometheus text page; -1 when absent.
double sample(const std::string& page, const std::string& series) {
  std::istringstream lines(page);
  for (std::string line; std::getline(lines, line);) {
    if (line.rfind(series + " ", 0) == 0) {
      return std::stod(line.substr(series.size() + 1));
    }
  }
  return -1.0;
}

}  // namespace

TEST(Vda5050Bridge, AVehicleDoesATransportTaskFromReleasesAndLeavesTrafficControlWhenItVanishes) {
  const std::string domain = std::to_string(test::uniqueDomain());
  setenv("FLEET_DDS_DOMAIN", domain.c_str(), 1);
  const std::vector<std::pair<std::string, std::string>> env = {{"FLEET_DDS_DOMAIN", domain}};
  test::MosquittoBroker broker({{"fleet-sim", "r1", "pw-r1"}});
  const auto dir = std::filesystem::temp_directory_path() / ("vda5050_bridge_" + domain);
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  std::ofstream(dir / "vehicles.json")
      << nlohmann::json{{"broker", {{"port", broker.port()}}},
                        {"map_id", "small_warehouse"},
                        {"vehicles", {{{"robot", "r1"}, {"password", "pw-r1"}}}}}
             .dump();
  std::ofstream(dir / "bridge.json")
      << nlohmann::json{{"broker",
                         {{"port", broker.port()},
                          {"username", test::MosquittoBroker::kMasterUser},
                          {"password", test::MosquittoBroker::kMasterPassword}}},
                        {"map_id", "small_warehouse"},
                        {"vehicles", {{{"manufacturer", "fleet-sim"}, {"serial", "r1"}, {"robot", "r1"}}}}}
             .dump();

  transport::Participant p;
  transport::Writer<msg::TaskAssignment> assign(p);
  transport::Writer<msg::TrafficRelease> releases(p);
  // What a traffic manager publishes first (transient-local): the bridge admits a vehicle only
  // once it knows the robot the roadmap was built for.
  transport::Writer<msg::Roadmap> roadmap(p);
  msg::Roadmap rm;
  rm.site = "one_robot";
  rm.robot_radius = 0.3;
  roadmap.write(rm);
  transport::Reader<msg::TaskStatus> statuses(p);
  transport::Reader<msg::RobotState> states(p);
  transport::Reader<msg::TrafficProgress> progress(p);

  const int ops = test::freePort();
  test::ChildProcess bridge(FLEET_BINARY_DIR "/services/vda5050_bridge/vda5050_bridge",
                            {"--config", (dir / "bridge.json").string(), "--log-level", "warn",
                             "--metrics-port", std::to_string(ops)},
                            env);
  auto sim = std::make_unique<test::ChildProcess>(
      FLEET_BINARY_DIR "/sim/src/fleet-sim",
      std::vector<std::string>{"--scenario", FLEET_SOURCE_DIR "/sim/scenarios/one_robot.json", "--clock",
                               "wall", "--duration", "100", "--vda5050", (dir / "vehicles.json").string(),
                               "--log-level", "warn"},
      env);

  std::vector<msg::TaskState> seen;
  int node = -1;
  bool follows = true;
  bool has_goal = false;
  int robot_states = 0;
  const auto pump = [&] {
    for (const auto& s : statuses.take()) {
      if (s.robot_id == "r1" && s.task_id == "t1" && (seen.empty() || seen.back() != s.state)) {
        seen.push_back(s.state);
      }
    }
    for (const auto& s : states.take()) {
      robot_states += s.robot_id == "r1" ? 1 : 0;
    }
    for (const auto& g : progress.take()) {
      if (g.robot_id == "r1") {
        node = g.node;
        follows = g.follows;
        has_goal = g.has_goal;
      }
    }
  };
  const auto until = [&](const std::function<bool()>& pred, std::chrono::seconds timeout) {
    const auto end = std::chrono::steady_clock::now() + timeout;
    while (std::chrono::steady_clock::now() < end) {
      pump();
      if (pred()) {
        return true;
      }
      std::this_thread::sleep_for(50ms);
    }
    return false;
  };
  ASSERT_TRUE(until([&] { return robot_states > 0; }, 30s)) << "the bridge never reported r1";

  // Bad input, published with the master's credentials onto r1's topics and a stranger's.
  mqtt::ClientOptions mo;
  mo.port = broker.port();
  mo.client_id = "intruder";
  mo.username = test::MosquittoBroker::kMasterUser;
  mo.password = test::MosquittoBroker::kMasterPassword;
  auto intruder = mqtt::Client::start(mo, {});
  ASSERT_TRUE(intruder) << intruder.error().message;
  ASSERT_TRUE(until([&] { return (*intruder)->connected(); }, 10s));
  const auto badState = [&](const std::string& topic, const std::string& payload) {
    ASSERT_TRUE((*intruder)->publish(topic, payload, 0, false));
    ASSERT_TRUE(until([&] { return !follows; }, 10s)) << "not faulted by " << payload;
    ASSERT_TRUE(until([&] { return follows; }, 10s)) << "not back after its next good state";
  };
  badState("uagv/v2/fleet-sim/r1/state", R"({"headerId": 1, "driving": "yes"})");
  nlohmann::json elsewhere = {
      {"headerId", 9},
      {"timestamp", "2026-11-26T00:00:00.000Z"},
      {"version", "2.1.0"},
      {"manufacturer", "fleet-sim"},
      {"serialNumber", "r1"},
      {"orderId", ""},
      {"orderUpdateId", 0},
      {"lastNodeId", ""},
      {"lastNodeSequenceId", 0},
      {"driving", false},
      {"operatingMode", "AUTOMATIC"},
      {"nodeStates", nlohmann::json::array()},
      {"edgeStates", nlohmann::json::array()},
      {"actionStates", nlohmann::json::array()},
      {"batteryState", {{"batteryCharge", 50.0}, {"charging", false}}},
      {"errors", nlohmann::json::array()},
      {"safetyState", {{"eStop", "NONE"}, {"fieldViolation", false}}},
      {"agvPosition",
       {{"x", 1.0}, {"y", 1.0}, {"theta", 0.0}, {"mapId", "other_site"}, {"positionInitialized", true}}}};
  badState("uagv/v2/fleet-sim/r1/state", elsewhere.dump());
  ASSERT_TRUE(
      (*intruder)->publish("uagv/v2/fleet-sim/r9/state", elsewhere.dump(), 0, false));  // unknown serial
  std::this_thread::sleep_for(500ms);
  pump();
  EXPECT_TRUE(follows) << "an unknown serial's message disturbed r1";
  EXPECT_EQ(bridge.wait(0ms), -1) << "the bridge exited on bad input";

  msg::TaskAssignment a;
  a.robot_id = "r1";
  a.task_id = "t1";
  a.revision = 1;
  a.goals = {{{8.5, 1.75, 0.0}, "P-1", msg::GoalAction::Load, 1.0},
             {{6.5, 1.75, 0.0}, "D-1", msg::GoalAction::Unload, 1.0}};
  assign.write(a);
  ASSERT_TRUE(until([&] { return has_goal; }, 10s)) << "the goal did not reach the traffic progress";

  releases.write(
      release(1, {{1000, 4.0}, {1001, 4.0}, {1002, 4.5}, {1003, 5.0}, {1004, 5.5}, {1005, 6.0}}, false));
  ASSERT_TRUE(until([&] { return node == 1005; }, 40s))
      << "did not reach the first base's end; at node " << node;
  releases.write(
      release(2, {{1005, 6.0}, {1006, 6.5}, {1007, 7.0}, {1008, 7.5}, {1009, 8.0}, {1010, 8.5}}, true));
  ASSERT_TRUE(until([&] { return !seen.empty() && seen.back() == msg::TaskState::Delivering; }, 40s))
      << "no pick at the end of the band; at node " << node;
  releases.write(release(3, {{1010, 8.5}, {1009, 8.0}, {1008, 7.5}, {1007, 7.0}, {1006, 6.5}}, true));
  ASSERT_TRUE(until([&] { return !seen.empty() && seen.back() == msg::TaskState::Done; }, 40s))
      << "not done; at node " << node;
  EXPECT_EQ(node, 1006);
  const std::vector<msg::TaskState> expected = {msg::TaskState::Assigned,  msg::TaskState::EnRoute,
                                                msg::TaskState::Loading,   msg::TaskState::Delivering,
                                                msg::TaskState::Unloading, msg::TaskState::Done};
  EXPECT_EQ(seen, expected);

  // The ops port: live and ready, and the metrics count what happened above.
  EXPECT_EQ(status(ops, "/livez"), 200);
  EXPECT_EQ(status(ops, "/readyz"), 200);
  std::string page;
  ASSERT_EQ(status(ops, "/metrics", &page), 200);
  EXPECT_GT(sample(page, "vda5050_bridge_mqtt_messages_received_total"), 10.0) << page;
  EXPECT_GE(sample(page, "vda5050_bridge_orders_total"), 1.0) << page;
  EXPECT_GE(sample(page, "vda5050_bridge_order_updates_total"), 1.0) << page;
  EXPECT_GE(sample(page, "vda5050_bridge_mqtt_messages_sent_total"), 3.0) << page;
  EXPECT_EQ(sample(page, "vda5050_bridge_vehicles{health=\"online\"}"), 1.0) << page;
  EXPECT_GE(sample(page, "vda5050_bridge_rejected_samples_total{reason=\"other_map\"}"), 1.0) << page;
  EXPECT_GE(sample(page, "vda5050_bridge_rejected_samples_total{reason=\"unknown_serial\"}"), 1.0) << page;
  EXPECT_GT(sample(page, "vda5050_bridge_cycle_seconds_count"), 10.0) << page;
  {
    const auto file = dir / "bridge.prom";
    std::ofstream(file) << page;
    const auto check =
        std::system(("promtool check metrics < " + file.string() + " > /dev/null 2>&1").c_str());
    EXPECT_EQ(check, 0) << "promtool check metrics failed on:\n" << page;
  }

  // A broker restart: the bridge and the vehicle reconnect, RobotState flows again. While the
  // broker is away the bridge is live but not ready.
  broker.stop();
  const auto notReady = [&] { return status(ops, "/readyz") == 503; };
  EXPECT_TRUE(until(notReady, 10s)) << "ready without a broker";
  EXPECT_EQ(status(ops, "/livez"), 200);
  broker.start();
  EXPECT_TRUE(until([&] { return status(ops, "/readyz") == 200; }, 30s))
      << "not ready again with the broker back";
  robot_states = 0;
  ASSERT_TRUE(until([&] { return robot_states > 3; }, 30s)) << "no RobotState after the broker restart";
  ASSERT_TRUE(follows);

  // The vehicle vanishes: the broker's last will takes it out of traffic control.
  sim->kill(SIGKILL);
  sim.reset();
  ASSERT_TRUE(until([&] { return !follows; }, 20s)) << "still in traffic control after its last will";
  pump();
  robot_states = 0;
  std::this_thread::sleep_for(1s);
  pump();
  EXPECT_EQ(robot_states, 0) << "RobotState still published for an offline vehicle";
  EXPECT_EQ(bridge.wait(0ms), -1) << "the bridge exited";
  std::filesystem::remove_all(dir);
}
