// End to end in the simulator, lockstep: the fleet manager assigns a transport task, the robot agent
// drives the simulated robot to the pickup and the drop-off, and the task is done with no contact.

#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <thread>

#include "fleet/transport/dds.hpp"
#include "fleet_stack.hpp"
#include "test_process.hpp"

using namespace fleet;
using namespace std::chrono_literals;
using nlohmann::json;

TEST(FleetScenario, OneRobotDeliversATransportTaskWithoutContact) {
  const auto run = test::freshRun("fleet_scn_");
  const auto& dir = run.dir;
  const std::string scenario = FLEET_SOURCE_DIR "/sim/scenarios/one_robot.json";
  const test::ManagerAndAgent fleet(dir, scenario, run.domain, {"--clock", "lockstep", "--id", "agents"});
  const auto& env = fleet.env;

  test::TaskClient client;
  transport::Reader<msg::TaskEvent> events(client.participant);
  const auto deadline = std::chrono::steady_clock::now() + 30s;
  const msg::Task t = test::transportTask("job-1", "P-2", "D-1");
  const auto ack = client.submit(t, 30s);
  ASSERT_TRUE(ack) << "no acknowledgement from the fleet manager";
  ASSERT_TRUE(ack->result == msg::AckResult::Stored || ack->result == msg::AckResult::Duplicate)
      << ack->detail;

  test::ChildProcess sim(FLEET_BINARY_DIR "/sim/src/fleet-sim",
                         {"--scenario", scenario, "--clock", "lockstep", "--participants",
                          test::ManagerAndAgent::kLockstepParticipants, "--duration", "200", "--summary",
                          (dir / "summary.json").string(), "--log-level", "warn"},
                         env);
  std::vector<msg::TaskState> seen;
  while (std::chrono::steady_clock::now() < deadline + 200s &&
         (seen.empty() || seen.back() != msg::TaskState::Done)) {
    events.waitForData(100ms);
    for (const auto& e : events.take()) {
      if (e.task_id == "job-1" && (seen.empty() || seen.back() != e.state)) {
        seen.push_back(e.state);
      }
    }
    if (sim.wait(1ms) >= 0) {
      for (const auto& e : events.take()) {
        if (e.task_id == "job-1" && (seen.empty() || seen.back() != e.state)) {
          seen.push_back(e.state);
        }
      }
      break;
    }
  }
  ASSERT_FALSE(seen.empty());
  EXPECT_EQ(seen.back(), msg::TaskState::Done);
  const std::vector<msg::TaskState> happy = {
      msg::TaskState::Queued,     msg::TaskState::Assigned,  msg::TaskState::EnRoute, msg::TaskState::Loading,
      msg::TaskState::Delivering, msg::TaskState::Unloading, msg::TaskState::Done};
  EXPECT_EQ(seen, happy);
  ASSERT_EQ(sim.wait(120s), 0) << "the simulator did not finish";
  const json summary = json::parse(std::ifstream(dir / "summary.json"));
  EXPECT_EQ(summary["contacts"]["robot_shelf"], 0);
  EXPECT_EQ(summary["contacts"]["robot_robot"], 0);
  EXPECT_EQ(summary["lockstep_step_timeouts"], 0);
  EXPECT_GT(summary["per_robot"]["r1"]["distance_m"].get<double>(), 10.0);
  std::filesystem::remove_all(dir);
}
