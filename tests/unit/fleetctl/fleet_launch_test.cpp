// The load test's fleet stage alone: the processes it would start and the files it writes, for
// a plan of agents, a stalled robot and a drop fault; nothing is started.
#include "fleet_launch.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>

namespace fleet::ctl {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

const std::string kSmall = std::string(FLEET_SOURCE_DIR) + "/sim/scenarios/small_warehouse.json";

std::vector<std::string> names(const std::vector<ProcessSpec>& specs) {
  std::vector<std::string> n;
  for (const auto& s : specs) {
    n.push_back(s.name);
  }
  return n;
}

std::string argAfter(const ProcessSpec& s, const std::string& flag) {
  const auto it = std::find(s.args.begin(), s.args.end(), flag);
  return it == s.args.end() || it + 1 == s.args.end() ? "" : *(it + 1);
}

std::string envOf(const ProcessSpec& s, const std::string& key) {
  for (const auto& [k, v] : s.env) {
    if (k == key) {
      return v;
    }
  }
  return "";
}

struct FleetLaunchTest : ::testing::Test {
  fs::path out = fs::temp_directory_path() / ("loadtest-launch-" + std::to_string(::getpid()));
  LoadtestOptions o;
  void SetUp() override {
    fs::remove_all(out);
    fs::create_directories(out);
    o.scenario = kSmall;
    o.binDir = "/opt/fleet";
    o.domain = 150;
    o.port = 18080;
  }
  void TearDown() override { fs::remove_all(out); }
};

TEST_F(FleetLaunchTest, AStalledRobotRunsAloneAndTheRestRoundRobinOverTheAgents) {
  o.agents = 2;
  auto run = prepareScenario(o, out);
  ASSERT_TRUE(run);
  const std::vector<Fault> faults = *parseFaults({"stall:r3@10+5"});
  auto plan = planFleet(o, *run, faults, out, nullptr);
  ASSERT_TRUE(plan) << plan.error().message;
  EXPECT_EQ(names(plan->specs),
            (std::vector<std::string>{"fleet_manager", "wms_adapter", "risk_map", "traffic_manager",
                                      "agent-0", "agent-1", "agent-r3"}));
  EXPECT_EQ(plan->agentOfRobot.at("r1"), "agent-0");
  EXPECT_EQ(plan->agentOfRobot.at("r2"), "agent-1");
  EXPECT_EQ(plan->agentOfRobot.at("r3"), "agent-r3");
  EXPECT_EQ(plan->agentOfRobot.at("r4"), "agent-0");  // r3 is skipped in the round robin
  EXPECT_EQ(argAfter(plan->specs[6], "--robots"), "r3");
  EXPECT_EQ(plan->robotsOfProcess.at("agent-0").size() + plan->robotsOfProcess.at("agent-1").size(), 19u);
  // The simulator waits for the risk map, the three agent processes and the traffic manager.
  EXPECT_EQ(plan->sim.name, "fleet-sim");
  EXPECT_EQ(argAfter(plan->sim, "--participants"), "5");
  EXPECT_EQ(plan->sim.exe, "/opt/fleet/sim/src/fleet-sim");
  EXPECT_EQ(argAfter(plan->specs[1], "--port"), "18080");
  for (const auto& s : plan->specs) {
    EXPECT_EQ(envOf(s, "FLEET_DDS_DOMAIN"), "150") << s.name;
    EXPECT_EQ(envOf(s, "CYCLONEDDS_URI"), "") << s.name;
    EXPECT_EQ(s.log, (fs::absolute(out) / (s.name + ".log")).string());
  }
  // The services' configuration: the manager's store and admission, the traffic manager's site.
  json manager = json::parse(std::ifstream(out / "manager.json"));
  EXPECT_EQ(manager["db"], fs::absolute(out / "fleet.db").string());
  EXPECT_EQ(manager["station_capacity"], "queue");
  json tm = json::parse(std::ifstream(out / "traffic_manager.json"));
  EXPECT_EQ(tm["site"], run->siteFile);
  EXPECT_EQ(tm["lockstep"], true);
  json risk = json::parse(std::ifstream(out / "risk_map.json"));
  EXPECT_EQ(risk["grid"]["resolution"], 0.1);
}

// `--guidance W` reaches both services that build the roadmap (the traffic manager plans on it, the
// fleet manager costs tasks and predicts arrivals on it), and without it neither is given one.
TEST_F(FleetLaunchTest, GuidanceGoesToTheTrafficAndFleetManagersAlike) {
  auto run = prepareScenario(o, out);
  ASSERT_TRUE(run);
  ASSERT_TRUE(planFleet(o, *run, {}, out, nullptr));
  EXPECT_FALSE(json::parse(std::ifstream(out / "manager.json")).contains("roadmap"));
  EXPECT_FALSE(json::parse(std::ifstream(out / "traffic_manager.json")).contains("roadmap"));
  o.guidance = 0.5;
  ASSERT_TRUE(planFleet(o, *run, {}, out, nullptr));
  EXPECT_EQ(json::parse(std::ifstream(out / "manager.json"))["roadmap"]["guidance"], 0.5);
  EXPECT_EQ(json::parse(std::ifstream(out / "traffic_manager.json"))["roadmap"]["guidance"], 0.5);
}

TEST_F(FleetLaunchTest, ADropFaultGivesEveryProcessItsLossyCycloneConfiguration) {
  auto run = prepareScenario(o, out);
  ASSERT_TRUE(run);
  auto plan = planFleet(o, *run, *parseFaults({"drop-dds=0.05"}), out, nullptr);
  ASSERT_TRUE(plan);
  const std::string uri = "file://" + fs::absolute(out / "cyclonedds.xml").string();
  for (const auto& s : plan->specs) {
    EXPECT_EQ(envOf(s, "CYCLONEDDS_URI"), uri) << s.name;
  }
  EXPECT_EQ(envOf(plan->sim, "CYCLONEDDS_URI"), uri);
  std::ifstream in(out / "cyclonedds.xml");
  std::string xml;
  std::getline(in, xml, '\0');
  EXPECT_NE(xml.find("<XmitLossiness>50</XmitLossiness>"), std::string::npos) << xml;  // per mille
}

TEST_F(FleetLaunchTest, DdsSecurityNeedsEveryIdentityAndNoDropFault) {
  o.ddsSecurity = (out / "security").string();
  auto missing = checkDdsSecurity(o, 0.0);
  ASSERT_FALSE(missing);
  EXPECT_NE(missing.error().message.find("no identity for fleet-manager, wms-adapter"), std::string::npos);
  EXPECT_NE(missing.error().message.find("ca.key"), std::string::npos);
  auto both = checkDdsSecurity(o, 0.1);
  ASSERT_FALSE(both);
  EXPECT_NE(both.error().message.find("drop-packets"), std::string::npos);
  for (const char* id : {"fleet-manager", "wms-adapter", "risk-map", "traffic-manager", "simulator"}) {
    fs::create_directories(out / "security" / id);
    std::ofstream(out / "security" / id / "cyclonedds.xml") << "<CycloneDDS/>";
  }
  std::ofstream(out / "security" / "ca.key") << "key";
  EXPECT_TRUE(checkDdsSecurity(o, 0.0));
  // Each process joins as its identity.
  auto run = prepareScenario(o, out);
  ASSERT_TRUE(run);
  auto plan = planFleet(o, *run, {}, out, nullptr);
  ASSERT_TRUE(plan);
  EXPECT_EQ(envOf(plan->specs[0], "CYCLONEDDS_URI"),
            "file://" + fs::absolute(out / "security" / "fleet-manager" / "cyclonedds.xml").string());
  EXPECT_EQ(envOf(plan->specs[4], "CYCLONEDDS_URI"),
            "file://" + fs::absolute(out / "security" / "agent-0" / "cyclonedds.xml").string());
}

TEST_F(FleetLaunchTest, MoreVda5050VehiclesThanRobotsAreRefused) {
  o.scenario = std::string(FLEET_SOURCE_DIR) + "/sim/scenarios/two_robots.json";
  o.vda5050 = 3;
  auto run = prepareScenario(o, out);
  ASSERT_TRUE(run) << run.error().message;
  auto plan = planFleet(o, *run, {}, out, nullptr);
  ASSERT_FALSE(plan);
  EXPECT_NE(plan.error().message.find("--vda5050 3 needs at most 2 robots"), std::string::npos);
}

}  // namespace
}  // namespace fleet::ctl
