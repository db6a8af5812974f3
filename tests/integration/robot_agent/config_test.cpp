// robot_agent --config as an operator meets it: a good file starts the agents, a bad one stops the
// process at once (exit 2) with every problem named by file and key path.

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include "run_command.hpp"
#include "test_process.hpp"

namespace fs = std::filesystem;

namespace {

struct AgentRun {
  int code = -1;
  std::string output;
};

/// Runs robot_agent with `args` until it exits (bad input) or `seconds` pass (`timeout` ends a good
/// run, which would otherwise go on until stopped).
AgentRun runAgent(const std::string& args, int seconds) {
  const std::string cmd = "FLEET_DDS_DOMAIN=" + std::to_string(fleet::test::uniqueDomain()) +
                          " timeout --preserve-status -s INT " + std::to_string(seconds) +
                          " " FLEET_BINARY_DIR "/services/robot_agent/robot_agent " + args;
  const auto o = fleet::test::runCommand(cmd);
  return {o.code, o.output};
}

AgentRun agentWith(const std::string& configText, int seconds) {
  const fs::path cfg = fs::temp_directory_path() / ("agent_cfg_" + std::to_string(getpid()) + ".json");
  std::ofstream(cfg) << configText;
  auto r = runAgent(
      "--scenario " FLEET_SOURCE_DIR "/sim/scenarios/one_robot.json --clock wall --config " + cfg.string(),
      seconds);
  fs::remove(cfg);
  return r;
}

}  // namespace

TEST(RobotAgentConfig, BadFileStopsAtStartNamingEveryProblem) {
  const AgentRun r = agentWith(
      R"({"local_planner": "dwa", "dwa": {"w_risk": -2, "samples": 5}, "safety": {"stop_margin": "far"},
          "colour": "red"})",
      20);
  EXPECT_EQ(r.code, 2) << r.output;
  for (const char* what :
       {"dwa.w_risk", "dwa.samples: unknown key", "safety.stop_margin", "colour: unknown key"}) {
    EXPECT_NE(r.output.find(what), std::string::npos) << what << " not in:\n" << r.output;
  }
  EXPECT_NE(r.output.find("agent_cfg_"), std::string::npos) << "the file is not named:\n" << r.output;
}

TEST(RobotAgentConfig, UnknownPlannerInTheFileIsNamed) {
  const AgentRun r = agentWith(R"({"local_planner": "teleport"})", 20);
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("local_planner: no local planner named 'teleport'"), std::string::npos) << r.output;
}

TEST(RobotAgentConfig, GoodFileRunsTheConfiguredPlanner) {
  // Runs until `timeout` interrupts it (SIGINT: a clean stop, exit 0).
  const AgentRun r = agentWith(R"({"local_planner": "dwa", "dwa": {"w_risk": 2.0, "v_samples": 14}})", 3);
  EXPECT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("dwa"), std::string::npos) << r.output;
}

TEST(RobotAgentConfig, LineUpdatesAreOnByDefaultAndTheFileCanTurnThemOff) {
  const AgentRun on = agentWith(R"({})", 3);
  EXPECT_EQ(on.code, 0) << on.output;
  EXPECT_NE(on.output.find("wall faces for the line updates (on)"), std::string::npos) << on.output;
  const AgentRun off = agentWith(R"({"localization": {"lines": false}})", 3);
  EXPECT_EQ(off.code, 0) << off.output;
  EXPECT_NE(off.output.find("off: localization.lines is false"), std::string::npos) << off.output;
  const AgentRun bad = agentWith(R"({"localization": {"lines": "sometimes", "landmarks": false}})", 20);
  EXPECT_EQ(bad.code, 2) << bad.output;
  EXPECT_NE(bad.output.find("localization.lines"), std::string::npos) << bad.output;
  EXPECT_NE(bad.output.find("localization.landmarks: unknown key"), std::string::npos) << bad.output;
}

namespace {

/// robot_agent as deployed: a site and the robots standing on it, no simulator scenario.
AgentRun agentOnSite(const std::string& robots, int seconds) {
  return runAgent(
      "--site " FLEET_SOURCE_DIR "/sim/scenarios/small_warehouse_12_parking.site.json --clock wall " + robots,
      seconds);
}

}  // namespace

TEST(RobotAgentSite, RunsTheRobotsGivenOnASite) {
  const AgentRun r = agentOnSite("--robot r1@PARK-1 --robot r2@5.0,1.25,1.5708", 3);
  EXPECT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("2 robot"), std::string::npos) << r.output;
}

TEST(RobotAgentSite, BadRobotsAreNamedAndNothingStarts) {
  const AgentRun r = agentOnSite(
      "--robot r1@NOPE --robot 'r 2@PARK-2' --robot r3@0.1,0.1,0 --robot r4@PARK-4 "
      "--robot r4@PARK-5",
      20);
  EXPECT_EQ(r.code, 2) << r.output;
  for (const char* what :
       {"--robot r1@NOPE: 'NOPE' is neither a station of site 'small-warehouse-12-parking'",
        "--robot r 2@PARK-2: expected ID@STATION", "--robot r3@0.1,0.1,0: a robot of radius",
        "--robot r4@PARK-5: robot 'r4' is given twice"}) {
    EXPECT_NE(r.output.find(what), std::string::npos) << what << " not in:\n" << r.output;
  }
  const AgentRun none = agentOnSite("", 20);
  EXPECT_EQ(none.code, 2) << none.output;
  EXPECT_NE(none.output.find("--site needs at least one --robot"), std::string::npos) << none.output;
}
