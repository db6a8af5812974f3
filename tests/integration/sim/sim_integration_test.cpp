// Two processes over loopback DDS: fleet-sim (child) and a robot agent stand-in (this test) that
// registers for lockstep, reads SensorFrame/Clock/GroundTruth and drives a robot with VelocityCommand.

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <thread>

#include "fleet/sim/replay.hpp"
#include "fleet/transport/dds.hpp"
#include "test_process.hpp"

using namespace fleet;
using namespace fleet::transport;
using namespace std::chrono_literals;

namespace {

const std::string kSim = FLEET_BINARY_DIR "/sim/src/fleet-sim";
const std::string kScenarios = FLEET_SOURCE_DIR "/sim/scenarios/";

std::string slurp(const std::string& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::string domain() {
  return std::to_string(test::uniqueDomain());
}

struct TempDir {
  std::filesystem::path path;
  TempDir() : path(std::filesystem::temp_directory_path() / ("sim_it_" + std::to_string(::getpid()))) {
    std::filesystem::create_directories(path);
  }
  ~TempDir() { std::filesystem::remove_all(path); }
  std::string operator/(const std::string& f) const { return (path / f).string(); }
};

struct AgentRun {
  std::int64_t lastStep = -1;
  std::int64_t clocks = 0;
  bool stepsInOrder = true;
  bool stampsMatchClock = true;
  std::size_t framesForR1 = 0;
  std::size_t rays = 0;
  double finalX = 0.0;
  double finalY = 0.0;
  double startX = 0.0;
  int exitCode = -1;
};

// The agent side of the lockstep protocol, as robot_agent speaks it: a command writer per robot
// (each in its robot's partition), matched before registering with StepDone(-1) until the first
// Clock; then for each Clock(k): read the frames of step k, command every robot, acknowledge with
// StepDone(k) naming the last command written for each robot.
AgentRun runLockstep(const std::string& scenario, double duration, const std::string& replay,
                     const std::string& summary, double v) {
  setenv("FLEET_DDS_DOMAIN", domain().c_str(), 1);
  std::vector<std::string> robots;
  const auto scenarioJson = nlohmann::json::parse(slurp(kScenarios + scenario));
  for (const auto& r : scenarioJson["robots"]) {
    robots.push_back(r["id"].get<std::string>());
  }
  Participant p;
  Writer<msg::StepDone> done(p);
  Writer<msg::VelocityCommand> cmd(p, qos::command(true));
  std::vector<std::string> commanded = robots;
  commanded.push_back("no-such-robot");  // its writer, too, before registering
  cmd.forRobots(commanded);
  std::map<std::string, std::uint32_t> seq;  // per robot: the last command's
  auto command = [&](msg::VelocityCommand c) {
    c.seq = ++seq[c.robot_id];
    cmd.write(c);
  };
  Reader<msg::Clock> clock(p);
  Reader<msg::SensorFrame> frames(p, qos::sensor(true));
  Reader<msg::GroundTruth> truth(p);
  test::ChildProcess sim(kSim,
                         {"--scenario", kScenarios + scenario, "--clock", "lockstep", "--participants", "1",
                          "--duration", std::to_string(duration), "--replay", replay, "--summary", summary,
                          "--step-timeout-ms", "10000", "--log-level", "warn"},
                         {{"FLEET_DDS_DOMAIN", domain()}});
  AgentRun run;
  const auto total = static_cast<std::int64_t>(std::llround(duration / 0.1));
  const auto deadline = std::chrono::steady_clock::now() + 60s;
  bool registered = false;
  while (run.lastStep < total && std::chrono::steady_clock::now() < deadline) {
    if (!registered && cmd.matchedReaders() > 0) {
      done.write({"agent", msg::StepDone::kRegister});
    }
    clock.waitForData(registered ? 1000ms : 100ms);
    for (const auto& c : clock.take()) {
      registered = true;
      ++run.clocks;
      run.stepsInOrder = run.stepsInOrder && c.step == run.lastStep + 1 && c.lockstep;
      run.lastStep = c.step;
      for (const auto& f : frames.take()) {
        run.stampsMatchClock = run.stampsMatchClock && f.stamp_ns == c.sim_time_ns;
        if (f.robot_id == "r1") {
          ++run.framesForR1;
          run.rays = f.ranges.size();
        }
      }
      for (const auto& g : truth.take()) {
        for (const auto& b : g.bodies) {
          if (b.id == "r1") {
            if (g.step == 0) {
              run.startX = b.pose.x;
            }
            run.finalX = b.pose.x;
            run.finalY = b.pose.y;
          }
        }
      }
      for (std::size_t i = 0; i < robots.size(); ++i) {
        // Deterministic commands: a function of the step and the robot only.
        command({robots[i], v, 0.3 * std::sin(0.2 * static_cast<double>(c.step) + static_cast<double>(i)),
                 c.sim_time_ns, 0});
      }
      if (c.step == 5 && robots.size() > 2) {
        // Bad input over the wire: NaN is ignored, an over-limit speed clamped, both counted.
        command({robots[1], std::nan(""), 0.0, c.sim_time_ns, 0});
        command({robots[2], 50.0, 0.0, c.sim_time_ns, 0});
        command({"no-such-robot", 0.1, 0.0, c.sim_time_ns, 0});
      }
      msg::StepDone d{"agent", c.step, {}};
      for (const auto& [robot, last] : seq) {
        d.commands.push_back({robot, last});
      }
      done.write(d);
    }
  }
  run.exitCode = sim.wait(30s);
  return run;
}

}  // namespace

TEST(SimLockstep, AgentDrivesRobotStepByStep) {
  TempDir dir;
  // circle_swap: r1 starts at (12.5, 7.5) facing the centre (-x).
  const AgentRun run = runLockstep("circle_swap.json", 3.0, dir / "r.jsonl.gz", dir / "s.json", 0.5);
  EXPECT_EQ(run.exitCode, 0);
  EXPECT_EQ(run.lastStep, 30);
  EXPECT_EQ(run.clocks, 31);
  EXPECT_TRUE(run.stepsInOrder);
  EXPECT_TRUE(run.stampsMatchClock);
  EXPECT_EQ(run.framesForR1, 31U);  // 10 Hz sensors at dt = 0.1: one frame per step
  EXPECT_EQ(run.rays, 72U);
  // About 0.5 m/s for 3 s minus the 0.5 s ramp (slip noise 1 %), towards the centre.
  EXPECT_NEAR(run.startX - run.finalX, 1.375, 0.15);
  const auto s = nlohmann::json::parse(slurp(dir / "s.json"));
  EXPECT_EQ(s["lockstep_step_timeouts"], 0);
  EXPECT_EQ(s["steps"], 30);
  EXPECT_EQ(s["commands"]["timeouts"], 0);  // a command every step: never timed out
  EXPECT_EQ(s["commands"]["nan_ignored"], 1);
  EXPECT_EQ(s["commands"]["clamped"], 1);
  EXPECT_EQ(s["commands"]["unknown_robot"], 1);
}

TEST(SimLockstep, SameSeedGivesByteIdenticalReplays) {
  TempDir dir;
  const AgentRun a = runLockstep("small_warehouse.json", 4.0, dir / "a.jsonl.gz", dir / "a.json", 0.4);
  const AgentRun b = runLockstep("small_warehouse.json", 4.0, dir / "b.jsonl.gz", dir / "b.json", 0.4);
  ASSERT_EQ(a.exitCode, 0);
  ASSERT_EQ(b.exitCode, 0);
  const std::string ra = slurp(dir / "a.jsonl.gz");
  ASSERT_GT(ra.size(), 100U);
  EXPECT_EQ(ra, slurp(dir / "b.jsonl.gz"));
  EXPECT_EQ(slurp(dir / "a.json"), slurp(dir / "b.json"));
  // And the robots did move under the agent's commands.
  auto lines = sim::readReplayLines(dir / "a.jsonl.gz");
  ASSERT_TRUE(lines);
  const auto first = nlohmann::json::parse((*lines)[1]);
  const auto last = nlohmann::json::parse(lines->back());
  EXPECT_NE(first["robots"][0][1], last["robots"][0][1]);
}

TEST(SimLockstep, SilentParticipantCostsOneTimeoutPerStep) {
  TempDir dir;
  setenv("FLEET_DDS_DOMAIN", domain().c_str(), 1);
  Participant p;
  Writer<msg::StepDone> done(p);
  Reader<msg::Clock> clock(p);
  test::ChildProcess sim(
      kSim,
      {"--scenario", kScenarios + "circle_swap.json", "--clock", "lockstep", "--participants", "1",
       "--duration", "0.5", "--summary", dir / "s.json", "--step-timeout-ms", "50", "--log-level", "error"},
      {{"FLEET_DDS_DOMAIN", domain()}});
  const auto deadline = std::chrono::steady_clock::now() + 20s;
  while (clock.take().empty() && std::chrono::steady_clock::now() < deadline) {
    done.write({"mute", msg::StepDone::kRegister});  // registers, then never acknowledges a step
    std::this_thread::sleep_for(50ms);
  }
  ASSERT_EQ(sim.wait(30s), 0);
  const auto s = nlohmann::json::parse(slurp(dir / "s.json"));
  EXPECT_EQ(s["lockstep_step_timeouts"], 5);
}

TEST(SimCli, BadScenarioIsRefusedWithEveryProblem) {
  TempDir dir;
  const std::string bad = dir / "bad.json";
  std::ofstream(bad)
      << R"({"name": "bad", "map": {"rows": ["@@@@@@", "@....@", "@....@", "@@@@@@"], "resolution": 1.0},
    "robots": [{"id": "a", "start": [0.5, 0.5]}, {"id": "b", "start_station": "X"}],
    "humans": {"speed_mean": -1}})";
  const std::string cmd = kSim + " --scenario " + bad + " --validate 2> " + (dir / "err.txt");
  const int rc = std::system(cmd.c_str());
  EXPECT_EQ(WEXITSTATUS(rc), 2);
  const std::string err = slurp(dir / "err.txt");
  EXPECT_NE(err.find("robot 'a'"), std::string::npos) << err;
  EXPECT_NE(err.find("unknown station 'X'"), std::string::npos) << err;
  EXPECT_NE(err.find("humans.speed_mean"), std::string::npos) << err;
  EXPECT_NE(err.find(bad), std::string::npos) << err;
}

TEST(SimWall, RunsInRealTimeAndWritesViewer) {
  TempDir dir;
  setenv("FLEET_DDS_DOMAIN", domain().c_str(), 1);
  Participant p;
  Reader<msg::Clock> clock(p);
  Reader<msg::PredictedDiscs> discs(p);
  const auto t0 = std::chrono::steady_clock::now();
  test::ChildProcess sim(
      kSim,
      {"--scenario", kScenarios + "aisle_crossing.json", "--clock", "wall", "--duration", "1.5", "--replay",
       dir / "r.jsonl.gz", "--html", dir / "v.html", "--log-level", "warn"},
      {{"FLEET_DDS_DOMAIN", domain()}});
  std::int64_t clocks = 0;
  std::size_t humanDiscs = 0;
  while (sim.wait(10ms) < 0 && std::chrono::steady_clock::now() - t0 < 30s) {
    for (const auto& c : clock.take()) {
      EXPECT_FALSE(c.lockstep);
      ++clocks;
    }
    for (const auto& d : discs.take()) {
      EXPECT_EQ(d.kind, msg::SourceKind::Human);
      EXPECT_EQ(d.discs.size(), 7U);
      ++humanDiscs;
    }
  }
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_EQ(sim.wait(1s), 0);
  EXPECT_GE(wall, 1.4);  // 15 steps of 0.1 s paced by the wall clock
  EXPECT_GT(clocks, 5);  // some may be published before discovery completes
  EXPECT_GT(humanDiscs, 0U);
  const std::string html = slurp(dir / "v.html");
  EXPECT_NE(html.find("aisle-crossing"), std::string::npos);
}
