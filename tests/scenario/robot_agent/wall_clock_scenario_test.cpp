// End to end in the simulator on the wall clock (no lockstep: the simulator, the fleet manager and the
// robot agent each run in real time on their own timers): the manager assigns a transport task, the
// agent drives the simulated robot to the pickup and the drop-off, and the task is done with no
// contact. The lockstep counterpart is tests/scenario/fleet/fleet_scenario_test.cpp.

#include <gtest/gtest.h>

#include <chrono>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <thread>

#include "fleet/transport/dds.hpp"
#include "fleet_stack.hpp"
#include "test_process.hpp"

using namespace fleet;
using namespace std::chrono_literals;
using nlohmann::json;

TEST(WallClockScenario, OneRobotDeliversATransportTaskInRealTime) {
  const auto run = test::freshRun("agent_wall_scn_");
  const auto& dir = run.dir;
  const std::string scenario = FLEET_SOURCE_DIR "/sim/scenarios/one_robot.json";
  const test::ManagerAndAgent fleet(dir, scenario, run.domain, {"--clock", "wall", "--threads", "2"},
                                    {{"clock", "wall"}});
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
                         {"--scenario", scenario, "--clock", "wall", "--duration", "280", "--summary",
                          (dir / "summary.json").string(), "--log-level", "warn"},
                         env);
  const auto simStart = std::chrono::steady_clock::now();
  std::vector<msg::TaskState> seen;
  while (std::chrono::steady_clock::now() < deadline + 330s &&
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
  std::cout << "task done after "
            << std::chrono::duration<double>(std::chrono::steady_clock::now() - simStart).count()
            << " s of wall time\n";
  sim.kill(SIGINT);  // the simulator stops at once and still writes its summary
  ASSERT_EQ(sim.wait(60s), 0) << "the simulator did not finish";
  const json summary = json::parse(std::ifstream(dir / "summary.json"));
  EXPECT_EQ(summary["contacts"]["robot_shelf"], 0);
  EXPECT_EQ(summary["contacts"]["robot_robot"], 0);
  EXPECT_GT(summary["per_robot"]["r1"]["distance_m"].get<double>(), 10.0);
  std::filesystem::remove_all(dir);
}
