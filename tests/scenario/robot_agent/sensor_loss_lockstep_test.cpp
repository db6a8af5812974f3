// A robot whose sensor stream stops, end to end in lockstep: fleet-sim (with --sensor-outage: it
// keeps simulating r1 but publishes none of its SensorFrames for 6 s), fleet_manager and robot_agent
// as processes. Mid-task the robot must stop within its sensor timeout, stand still, report the
// fault (RobotState mode and a TaskStatus naming it), clear it, drive on when frames return and
// deliver, without contact. Delivering needs the ~0.7 m it rolled blind while braking: the first
// frame after the gap carries the simulator's wheel totals, from which the agent takes the motion
// since the last frame it got (with increments alone it kept the error, no landmark in view along
// the band corrected it, and it stalled at the next aisle mouth).

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "fleet/sim/replay.hpp"
#include "fleet/transport/dds.hpp"
#include "fleet_stack.hpp"
#include "test_process.hpp"

using namespace fleet;
using namespace std::chrono_literals;
using nlohmann::json;

TEST(AgentLockstep, ARobotWhoseSensorStreamStopsStopsReportsItAndResumes) {
  // The outage, simulated seconds: r1 drives along the parking band at full speed then (it leaves
  // its parking place once the traffic manager has heard every robot, about 3.5 s in).
  constexpr double kFrom = 8.0;
  constexpr double kTo = 14.0;
  constexpr double kSensorTimeout = 0.5;  // robot_agent's default --sensor-timeout
  const auto run = test::freshRun("agent_sensor_loss_");
  const auto& dir = run.dir;
  const std::string scenario = FLEET_SOURCE_DIR "/sim/scenarios/one_robot.json";
  const test::ManagerAndAgent fleet(dir, scenario, run.domain, {"--clock", "lockstep", "--id", "agents"});

  test::TaskClient client;
  transport::Reader<msg::TaskStatus> statuses(client.participant);
  const auto deadline = std::chrono::steady_clock::now() + 30s;
  const auto ack = client.submit(test::transportTask("job-1", "P-2", "D-1"), 30s);
  ASSERT_TRUE(ack) << "no acknowledgement from the fleet manager";

  const auto replayPath = (dir / "replay.jsonl.gz").string();
  test::ChildProcess sim(
      FLEET_BINARY_DIR "/sim/src/fleet-sim",
      {"--scenario", scenario, "--clock", "lockstep", "--participants",
       test::ManagerAndAgent::kLockstepParticipants, "--duration", "200", "--sensor-outage", "r1@8+6",
       "--replay", replayPath, "--summary", (dir / "summary.json").string(), "--log-level", "warn"},
      fleet.env);
  std::string faultReport;
  bool clearedAfterFault = false;
  bool delivered = false;
  // Until the simulator ends, then a few seconds more for the last reports.
  std::optional<std::chrono::steady_clock::time_point> simEnded;
  while (std::chrono::steady_clock::now() < deadline + 200s &&
         (!simEnded || std::chrono::steady_clock::now() < *simEnded + 3s)) {
    statuses.waitForData(100ms);
    for (const auto& s : statuses.take()) {
      if (s.error.find("sensor stream lost") != std::string::npos) {
        faultReport = s.error;
      } else if (!faultReport.empty() && s.error.empty()) {
        clearedAfterFault = true;
      }
      delivered = delivered || (s.task_id == "job-1" && s.state == msg::TaskState::Done);
    }
    if (!simEnded && sim.wait(1ms) >= 0) {
      simEnded = std::chrono::steady_clock::now();
    }
  }
  EXPECT_FALSE(faultReport.empty()) << "no TaskStatus named the lost sensor stream";
  EXPECT_TRUE(clearedAfterFault) << "no TaskStatus cleared the fault when frames came back";
  EXPECT_TRUE(delivered) << "the task was not done within 200 s of simulated time";
  sim.kill(SIGINT);
  ASSERT_GE(sim.wait(60s), 0);

  // The simulator's ground truth, every 0.1 s: [x, y, theta, v, battery, charging, mode, task].
  auto lines = sim::readReplayLines(replayPath);
  ASSERT_TRUE(lines) << lines.error().message;
  double vBefore = 0.0;
  double vMaxStill = 0.0;  // speed once the timeout and braking have passed
  double xStill = NAN;
  double yStill = NAN;
  double drift = 0.0;
  int faultSteps = 0;
  int movingAfter = 0;
  for (std::size_t i = 1; i < lines->size(); ++i) {
    const json step = json::parse((*lines)[i]);
    const double t = step["t"].get<double>();
    const auto& r = step["robots"][0];
    const double v = std::abs(r[3].get<double>());
    if (t >= kFrom - 1.0 && t < kFrom) {
      vBefore = std::max(vBefore, v);
    }
    // Timeout, then braking from at most 0.8 m/s at 1 m/s²: standing from kFrom + 1.5 s on.
    if (t >= kFrom + kSensorTimeout + 1.0 && t < kTo) {
      vMaxStill = std::max(vMaxStill, v);
      if (std::isnan(xStill)) {
        xStill = r[0].get<double>();
        yStill = r[1].get<double>();
      }
      drift = std::max(drift, std::hypot(r[0].get<double>() - xStill, r[1].get<double>() - yStill));
    }
    if (t >= kFrom && t < kTo && r[6] == "fault") {
      ++faultSteps;
    }
    if (t >= kTo + 1.0 && t < kTo + 10.0 && v > 0.1) {
      ++movingAfter;
    }
  }
  EXPECT_GT(vBefore, 0.2) << "the robot was not driving when the outage began";
  EXPECT_LT(vMaxStill, 1e-3) << "moved while it saw nothing";
  EXPECT_LT(drift, 0.01);
  EXPECT_GT(faultSteps, 30) << "RobotState did not report the fault (mode) during the outage";
  EXPECT_GT(movingAfter, 0) << "did not drive again once frames came back";
  const json summary = json::parse(std::ifstream(dir / "summary.json"));
  EXPECT_EQ(summary["contacts"]["robot_shelf"], 0);
  std::cout << faultReport << "; fault reported in " << faultSteps << " steps, speed before " << vBefore
            << " m/s, drift while blind " << drift << " m\n";
}
