// fleet-sim with a robot run as a VDA 5050 vehicle, over a real broker: it announces itself
// (connection, factsheet, state), follows an order sent over MQTT, counts a message it cannot
// read, and says OFFLINE when the simulation ends.

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <mutex>
#include <thread>

#include "fleet/mqtt/client.hpp"
#include "fleet/vda5050/connection.hpp"
#include "fleet/vda5050/factsheet.hpp"
#include "fleet/vda5050/order.hpp"
#include "fleet/vda5050/state.hpp"
#include "mosquitto_broker.hpp"
#include "test_process.hpp"

namespace fleet {
namespace {

using namespace std::chrono_literals;

const std::string kSim = FLEET_BINARY_DIR "/sim/src/fleet-sim";
const std::string kScenarios = FLEET_SOURCE_DIR "/sim/scenarios/";
const std::string kBase = "uagv/v2/fleet-sim/r1/";

TEST(FleetSimVda5050, ARobotRunsAsAVda5050VehicleOverTheBroker) {
  test::MosquittoBroker broker({{"fleet-sim", "r1", "pw-r1"}});
  const auto dir = std::filesystem::temp_directory_path() / ("fleet_sim_vda_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const auto config = dir / "vda5050.json";
  std::ofstream(config) << nlohmann::json{{"broker", {{"host", "127.0.0.1"}, {"port", broker.port()}}},
                                          {"map_id", "small_warehouse"},
                                          {"vehicles", {{{"robot", "r1"}, {"password", "pw-r1"}}}}}
                               .dump();

  std::mutex mutex;
  std::vector<std::pair<std::string, std::string>> got;
  mqtt::ClientOptions mo;
  mo.port = broker.port();
  mo.client_id = "master";
  mo.username = test::MosquittoBroker::kMasterUser;
  mo.password = test::MosquittoBroker::kMasterPassword;
  auto master = mqtt::Client::start(mo, [&](const std::string& t, const std::string& p) {
    std::lock_guard lock(mutex);
    got.emplace_back(t, p);
  });
  ASSERT_TRUE(master) << master.error().message;
  (*master)->subscribe(kBase + "#", 1);
  const auto last = [&](const std::string& topic) -> std::optional<std::string> {
    std::lock_guard lock(mutex);
    for (auto it = got.rbegin(); it != got.rend(); ++it) {
      if (it->first == kBase + topic) {
        return it->second;
      }
    }
    return std::nullopt;
  };
  const auto waitFor = [](const std::function<bool()>& pred, std::chrono::seconds timeout) {
    const auto end = std::chrono::steady_clock::now() + timeout;
    while (!pred() && std::chrono::steady_clock::now() < end) {
      std::this_thread::sleep_for(20ms);
    }
    return pred();
  };

  const auto summary = dir / "summary.json";
  test::ChildProcess sim(
      kSim,
      {"--scenario", kScenarios + "one_robot.json", "--clock", "lockstep", "--duration", "60", "--max-speed",
       "4", "--vda5050", config.string(), "--summary", summary.string(), "--log-level", "warn"},
      {{"FLEET_DDS_DOMAIN", std::to_string(test::uniqueDomain())}});

  ASSERT_TRUE(waitFor([&] { return last("state").has_value(); }, 20s)) << "no state from r1";
  ASSERT_TRUE(waitFor([&] { return last("factsheet").has_value(); }, 5s));
  const auto fs = vda5050::parseFactsheet(*last("factsheet"));
  ASSERT_TRUE(fs) << fs.error().message;
  EXPECT_GT(fs->width, 0.0);
  const auto online = vda5050::parseConnection(*last("connection"));
  ASSERT_TRUE(online);
  EXPECT_EQ(online->connectionState, "ONLINE");

  const auto s0 = vda5050::parseState(*last("state"));
  ASSERT_TRUE(s0) << s0.error().message;
  ASSERT_TRUE(s0->agvPosition);
  const auto p = *s0->agvPosition;
  vda5050::Order o;
  o.header = {1, vda5050::isoTimestamp(0), vda5050::kVersion, "fleet-sim", "r1"};
  o.orderId = "o1";
  o.nodes = {{"start", 0, true, vda5050::NodePosition{p.x, p.y, {}, 0.3, {}, "small_warehouse"}, {}},
             {"ahead",
              2,
              true,
              vda5050::NodePosition{
                  p.x + std::cos(p.theta), p.y + std::sin(p.theta), {}, 0.2, {}, "small_warehouse"},
              {}}};
  o.edges = {{"e1", 1, true, "start", "ahead", {}, {}, {}}};
  (*master)->publish(kBase + "order", "[1, 2]", 0, false);  // unreadable: counted, nothing else
  ASSERT_TRUE((*master)->publish(kBase + "order", vda5050::toJson(o).dump(), 0, false));
  ASSERT_TRUE(waitFor(
      [&] {
        const auto s = vda5050::parseState(last("state").value_or(""));
        return s && s->lastNodeId == "ahead" && !s->driving;
      },
      30s))
      << "r1 did not reach the ordered node; last state: " << last("state").value_or("none");
  const auto s1 = vda5050::parseState(*last("state"));
  EXPECT_NEAR(s1->agvPosition->x, p.x + std::cos(p.theta), 0.25);
  EXPECT_NEAR(s1->agvPosition->y, p.y + std::sin(p.theta), 0.25);

  ASSERT_EQ(sim.wait(60s), 0);
  ASSERT_TRUE(waitFor(
      [&] { return vda5050::parseConnection(*last("connection"))->connectionState == "OFFLINE"; }, 5s));
  std::ifstream in(summary);
  const auto j = nlohmann::json::parse(in);
  EXPECT_EQ(j.at("vda5050").at("refused_messages"), 1);
  EXPECT_GT(j.at("vda5050").at("states_sent").get<int>(), 5);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace fleet
