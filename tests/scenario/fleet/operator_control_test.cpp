// Operator control end to end in lockstep (fleet-sim, fleet_manager, robot_agent as processes, the
// simulator paced at 5x real time so the test can act mid-task): a task is paused while its robot
// drives - the robot stands still, holding the task -, resumed - it drives on -, then cancelled -
// the task ends cancelled, never delivered, and the robot drops it. Asserted on the simulator's
// ground truth and on the manager's task events.

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <thread>

#include "fleet/sim/replay.hpp"
#include "fleet/transport/dds.hpp"
#include "fleet_stack.hpp"
#include "test_process.hpp"

using namespace fleet;
using namespace std::chrono_literals;
using nlohmann::json;

namespace {

msg::Task operatorRequest(const std::string& id, const std::string& request, bool cancel,
                          msg::TaskControl c) {
  msg::Task t;
  t.task_id = id;
  t.request_id = request;
  t.cancel = cancel;
  t.control = c;
  return t;
}

}  // namespace

TEST(FleetScenario, PauseHoldsTheRobotResumeDrivesOnCancelEndsTheTask) {
  const auto run = test::freshRun("fleet_control_");
  const auto& dir = run.dir;
  const std::string scenario = FLEET_SOURCE_DIR "/sim/scenarios/one_robot.json";
  const test::ManagerAndAgent fleet(dir, scenario, run.domain, {"--clock", "lockstep", "--id", "agents"});

  test::TaskClient client;
  transport::Reader<msg::TaskEvent> events(client.participant);
  const auto stored = client.submit(test::transportTask("job-1", "P-2", "D-1"), 30s);
  ASSERT_TRUE(stored) << "no acknowledgement from the fleet manager";

  const auto replayPath = (dir / "replay.jsonl.gz").string();
  test::ChildProcess sim(
      FLEET_BINARY_DIR "/sim/src/fleet-sim",
      {"--scenario", scenario, "--clock", "lockstep", "--participants",
       test::ManagerAndAgent::kLockstepParticipants, "--duration", "150", "--max-speed", "5", "--replay",
       replayPath, "--summary", (dir / "summary.json").string(), "--log-level", "warn"},
      fleet.env);
  std::set<msg::TaskState> seen;
  auto watchFor = [&](msg::TaskState state, std::chrono::seconds wait) {
    const auto until = std::chrono::steady_clock::now() + wait;
    while (!seen.count(state) && std::chrono::steady_clock::now() < until) {
      events.waitForData(50ms);
      for (const auto& e : events.take()) {
        if (e.task_id == "job-1") {
          seen.insert(e.state);
        }
      }
    }
    return seen.count(state) > 0;
  };
  ASSERT_TRUE(watchFor(msg::TaskState::EnRoute, 30s));
  std::this_thread::sleep_for(1500ms);  // ~7 s simulated: driving to the pickup
  const auto paused =
      client.submit(operatorRequest("job-1", "req-pause", false, msg::TaskControl::Pause), 10s);
  ASSERT_TRUE(paused && paused->result == msg::AckResult::Stored) << (paused ? paused->detail : "no ack");
  std::this_thread::sleep_for(3s);  // ~15 s simulated held
  const auto resumed =
      client.submit(operatorRequest("job-1", "req-resume", false, msg::TaskControl::Resume), 10s);
  ASSERT_TRUE(resumed && resumed->result == msg::AckResult::Stored) << (resumed ? resumed->detail : "no ack");
  std::this_thread::sleep_for(2s);  // ~10 s simulated driving again
  const auto cancelled =
      client.submit(operatorRequest("job-1", "req-cancel", true, msg::TaskControl::None), 10s);
  ASSERT_TRUE(cancelled && cancelled->result == msg::AckResult::Stored)
      << (cancelled ? cancelled->detail : "no ack");
  EXPECT_TRUE(watchFor(msg::TaskState::Cancelled, 10s));
  std::this_thread::sleep_for(1s);  // a few simulated seconds after the cancel
  sim.kill(SIGINT);
  ASSERT_GE(sim.wait(60s), 0);
  EXPECT_FALSE(seen.count(msg::TaskState::Done)) << "a cancelled task was delivered";

  // Ground truth every 0.1 s: [x, y, theta, v, battery, charging, mode, task].
  auto lines = sim::readReplayLines(replayPath);
  ASSERT_TRUE(lines) << lines.error().message;
  double longestHold = 0.0;  // the longest stretch standing still with the task, in "waiting"
  double holdStart = -1.0;
  double drivenAfterHold = 0.0;
  double heldSince = -1.0;
  std::string lastTask = "?";
  for (std::size_t i = 1; i < lines->size(); ++i) {
    const json step = json::parse((*lines)[i]);
    const double t = step["t"].get<double>();
    const auto& r = step["robots"][0];
    const bool holding = r[6] == "waiting" && r[7] == "job-1" && std::abs(r[3].get<double>()) < 1e-3;
    if (holding) {
      if (holdStart < 0) {
        holdStart = t;
      }
      if (t - holdStart > longestHold) {
        longestHold = t - holdStart;
        heldSince = holdStart;
      }
    } else {
      holdStart = -1.0;
    }
    if (heldSince >= 0 && t > heldSince + longestHold + 0.5 && r[7] == "job-1") {
      drivenAfterHold = std::max(drivenAfterHold, std::abs(r[3].get<double>()));
    }
    lastTask = r[7].get<std::string>();
  }
  EXPECT_GT(longestHold, 5.0) << "the paused robot did not stand still with its task";
  EXPECT_GT(drivenAfterHold, 0.2) << "the resumed robot did not drive on";
  EXPECT_EQ(lastTask, "") << "the robot still carries the cancelled task";
  const json summary = json::parse(std::ifstream(dir / "summary.json"));
  EXPECT_EQ(summary["contacts"]["robot_shelf"], 0);
  std::cout << "held " << longestHold << " s from " << heldSince << " s, then up to " << drivenAfterHold
            << " m/s\n";
}
