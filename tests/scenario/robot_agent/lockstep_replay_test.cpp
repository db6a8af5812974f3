// Lockstep determinism with the real robot agent in reserved traffic: fleet-sim, traffic_manager
// and robot_agent (the scenario's robots stepped by a 2-thread worker pool, DWA local planner, no
// lanes) run the same seeded scenario twice with the same orders; the two replays and summaries are
// byte-identical, so neither thread timing nor DDS write order (between the agent's progress reports
// and the traffic manager's releases too) leaks into what the robots do.

#include <gtest/gtest.h>

#include <chrono>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>

#include "fleet/transport/dds.hpp"
#include "fleet_stack.hpp"
#include "test_process.hpp"

using namespace fleet;
using namespace std::chrono_literals;

namespace {

std::string slurp(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

}  // namespace

TEST(AgentLockstep, SameSeedAndOrdersGiveByteIdenticalReplays) {
  const std::string domain = std::to_string(test::uniqueDomain());
  setenv("FLEET_DDS_DOMAIN", domain.c_str(), 1);
  const auto dir = std::filesystem::temp_directory_path() / ("agent_replay_" + domain);
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const std::string scenario = FLEET_SOURCE_DIR "/sim/scenarios/small_warehouse.json";
  const std::vector<std::pair<std::string, std::string>> env = {{"FLEET_DDS_DOMAIN", domain}};

  // Orders for four robots, transient-local: each run's agent process receives the same ones.
  transport::Participant p;
  transport::Writer<msg::TaskAssignment> orders(p);
  transport::Reader<msg::TrafficRelease> releases(p);
  const std::vector<std::pair<std::string, msg::Goal>> plan = {
      {"r1", {{3.5, 17.0, -1.5708}, "P-1", msg::GoalAction::Load, 1.0}},
      {"r2", {{9.0, 17.0, -1.5708}, "P-2", msg::GoalAction::Load, 1.0}},
      {"r3", {{28.5, 4.0, 3.1416}, "D-1", msg::GoalAction::Unload, 1.0}},
      {"r4", {{28.5, 7.0, 3.1416}, "D-2", msg::GoalAction::Unload, 1.0}}};
  for (const auto& [robot, goal] : plan) {
    msg::TaskAssignment a;
    a.robot_id = robot;
    a.task_id = "job-" + robot;
    a.revision = 1;
    a.goals.push_back(goal);
    orders.write(a);
  }
  auto runOnce = [&](const std::string& tag) {
    // The previous run's agent must be gone from discovery first: its reader, still matched,
    // had acknowledged the orders already, so waitForAcks returned at once while the new agent
    // had not got them yet, and the second replay diverged (a clean-clone CI run, 2026-11-25).
    const auto gone = std::chrono::steady_clock::now() + 30s;
    while (orders.matchedReaders() > 0 && std::chrono::steady_clock::now() < gone) {
      std::this_thread::sleep_for(20ms);
    }
    EXPECT_EQ(orders.matchedReaders(), 0u) << "the previous run's agent is still matched";
    // Nor may the previous run's traffic manager be heard: its releases are transient-local.
    while (releases.matchedWriters() > 0 && std::chrono::steady_clock::now() < gone) {
      std::this_thread::sleep_for(20ms);
    }
    EXPECT_EQ(releases.matchedWriters(), 0u) << "the previous run's traffic manager is still matched";
    test::ChildProcess traffic(test::kTrafficManagerBinary, test::trafficManagerArgs(dir, scenario, true),
                               env);
    test::ChildProcess agent(FLEET_BINARY_DIR "/services/robot_agent/robot_agent",
                             {"--scenario", scenario, "--clock", "lockstep", "--id", "agents", "--threads",
                              "2", "--local-planner", "dwa", "--log-level", "warn"},
                             env);
    // The agent must hold the orders before the first step, or the two runs start differently (a
    // fixed wait after the match was not enough under CI load: r4's order came 4 steps late once).
    const auto until = std::chrono::steady_clock::now() + 30s;
    while (orders.matchedReaders() == 0 && std::chrono::steady_clock::now() < until) {
      std::this_thread::sleep_for(20ms);
    }
    EXPECT_TRUE(orders.waitForAcks(30s)) << "the agent did not acknowledge its orders";
    // Two lockstep participants: the agent process and the traffic manager.
    test::ChildProcess sim(
        FLEET_BINARY_DIR "/sim/src/fleet-sim",
        {"--scenario", scenario, "--clock", "lockstep", "--participants", "2", "--duration", "20", "--replay",
         (dir / (tag + ".jsonl.gz")).string(), "--summary", (dir / (tag + ".json")).string(),
         "--step-timeout-ms", "10000", "--log-level", "warn"},
        env);
    const int rc = sim.wait(120s);
    agent.kill(SIGTERM);  // a clean exit unregisters its reader at once (SIGKILL: a lease later)
    (void)agent.wait(20s);
    traffic.kill(SIGTERM);
    (void)traffic.wait(20s);
    return rc;
  };
  ASSERT_EQ(runOnce("a"), 0);
  ASSERT_EQ(runOnce("b"), 0);
  const std::string ra = slurp(dir / "a.jsonl.gz");
  ASSERT_GT(ra.size(), 100U);
  EXPECT_EQ(ra, slurp(dir / "b.jsonl.gz"));
  const std::string sa = slurp(dir / "a.json");
  EXPECT_EQ(sa, slurp(dir / "b.json"));
  const auto summary = nlohmann::json::parse(sa);
  EXPECT_EQ(summary["lockstep_step_timeouts"], 0);
  EXPECT_GT(summary["per_robot"]["r4"]["distance_m"].get<double>(), 1.0) << "the ordered robots moved";
  if (!HasFailure())
    std::filesystem::remove_all(dir);
}
