// The agent in reserved traffic against the real simulator in lockstep (sensor noise, wheel slip,
// the robot's acceleration limits), with this test as the traffic manager: r1 leaves its parking
// place (PARK-1, facing up the small warehouse's band) by a base that goes up 0.5 m and turns east
// along the band for 4.5 m. It must drive the base, keep to it round the corner, stop at its end
// (no further than 5 cm past it) and report every node it reached, the last one last.

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <thread>

#include "fleet/transport/dds.hpp"
#include "test_process.hpp"

using namespace fleet;
using namespace std::chrono_literals;

TEST(AgentLockstepReserved, DrivesItsBaseRoundACornerAndStopsAtItsEnd) {
  const std::string domain = std::to_string(test::uniqueDomain());
  setenv("FLEET_DDS_DOMAIN", domain.c_str(), 1);
  const auto dir = std::filesystem::temp_directory_path() / ("agent_reserved_" + domain);
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const std::string scenario = FLEET_SOURCE_DIR "/sim/scenarios/one_robot.json";
  const std::vector<std::pair<std::string, std::string>> env = {{"FLEET_DDS_DOMAIN", domain}};

  transport::Participant p;
  transport::Writer<msg::TrafficRelease> releases(p);
  transport::Reader<msg::TrafficProgress> progress(p);
  transport::Reader<msg::GroundTruth> truth(p);
  msg::TrafficRelease r;
  r.robot_id = "r1";
  r.epoch = 1;
  r.seq = 1;
  r.base = {{1000, 4.0, 1.25}, {1001, 4.0, 1.75}};  // PARK-1, then up
  for (int k = 1; k <= 9; ++k) {
    r.base.push_back({1001 + k, 4.0 + 0.5 * k, 1.75});  // east along the band to (8.5, 1.75)
  }
  releases.write(r);

  test::ChildProcess agent(
      FLEET_BINARY_DIR "/services/robot_agent/robot_agent",
      {"--scenario", scenario, "--clock", "lockstep", "--id", "agents", "--log-level", "warn"}, env);
  const auto until = std::chrono::steady_clock::now() + 30s;
  while (releases.matchedReaders() == 0 && std::chrono::steady_clock::now() < until) {
    std::this_thread::sleep_for(20ms);
  }
  ASSERT_TRUE(releases.waitForAcks(30s)) << "the agent did not take the release";
  test::ChildProcess sim(
      FLEET_BINARY_DIR "/sim/src/fleet-sim",
      {"--scenario", scenario, "--clock", "lockstep", "--participants", "1", "--duration", "25", "--summary",
       (dir / "summary.json").string(), "--step-timeout-ms", "5000", "--log-level", "warn"},
      env);
  double maxX = -1e9;
  double offBand = 0.0;  // |y - 1.75| once past the corner
  Pose2 last;
  std::vector<std::int32_t> nodes;
  const auto deadline = std::chrono::steady_clock::now() + 120s;
  bool simEnded = false;
  while (std::chrono::steady_clock::now() < deadline && !simEnded) {
    truth.waitForData(100ms);
    for (const auto& g : truth.take()) {
      for (const auto& b : g.bodies) {
        if (b.id == "r1") {
          last = b.pose;
          maxX = std::max(maxX, b.pose.x);
          if (b.pose.x > 4.6) {
            offBand = std::max(offBand, std::abs(b.pose.y - 1.75));
          }
        }
      }
    }
    for (const auto& t : progress.take()) {
      if (t.robot_id == "r1" && (nodes.empty() || nodes.back() != t.node)) {
        nodes.push_back(t.node);
      }
    }
    simEnded = sim.wait(1ms) >= 0;
  }
  ASSERT_TRUE(simEnded) << "the simulator did not finish";
  for (const auto& t : progress.take()) {
    if (t.robot_id == "r1" && (nodes.empty() || nodes.back() != t.node)) {
      nodes.push_back(t.node);
    }
  }
  std::cout << "r1 ended at " << last.x << ", " << last.y << "; furthest x " << maxX << "; off the band "
            << offBand << " m\n";
  EXPECT_LE(maxX, 8.5 + 0.05) << "overshot the end of the base";
  EXPECT_GE(last.x, 8.5 - 0.15) << "stopped short of the end of the base";
  EXPECT_LT(offBand, 0.15) << "left the released nodes";
  ASSERT_FALSE(nodes.empty());
  EXPECT_EQ(nodes.back(), 1010);
  EXPECT_TRUE(std::is_sorted(nodes.begin(), nodes.end())) << "nodes reported out of order";
  // (The topic keeps each robot's latest report (history 1) and this reader polls it every 100 ms
  // of wall time while the lockstep runs faster, so a report can be overwritten before it is read;
  // the contract allows that: reaching a node implies passing the ones before it. Requiring 8 of
  // the 9 failed about 1 run in 5 on a loaded machine.)
  EXPECT_GE(nodes.size(), 5u) << "most nodes never reported";
  const auto summary = nlohmann::json::parse(std::ifstream(dir / "summary.json"));
  EXPECT_EQ(summary["contacts"]["robot_shelf"], 0);
  EXPECT_EQ(summary["lockstep_step_timeouts"], 0);
  std::filesystem::remove_all(dir);
}
