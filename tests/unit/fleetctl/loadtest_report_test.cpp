// The load test's report stage alone: loadtest.json and the summary lines from a run folder's
// files and an accounting, without a fleet.
#include "loadtest_report.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

namespace fleet::ctl {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

TEST(LoadtestReport, ReadsTheRunFolderAndStatesTheAccountingAndTheAgents) {
  const fs::path out = fs::temp_directory_path() / ("loadtest-report-" + std::to_string(::getpid()));
  fs::remove_all(out);
  fs::create_directories(out);
  std::ofstream(out / "sim_summary.json") << json{
      {"sim_time_s", 120.0},
      {"contacts", {{"robot_robot", 0}}},
      {"min_separation_m",
       {{"robot_robot", 0.61}}}}.dump();
  std::ofstream(out / "agent-0_metrics.json") << json{
      {"id", "agent-0"},
      {"clock", "wall"},
      {"robots", 3},
      {"achieved_hz", 9.9},
      {"configured_hz", 10.0},
      {"overruns", 1},
      {"cycle_ms",
       {{"p50", 1.5}, {"p99", 4.0}, {"max", 9.0}}}}.dump();
  LoadtestOptions o;
  o.wallClock = true;  // no replay: the bound and the saturated window say why they are absent
  o.durationS = 120;
  RunOutcome run;
  run.scenario = "stage";
  run.robots = 3;
  run.agentNames = {"agent-0", "agent-1"};  // agent-1 left no metrics
  run.wallS = 60;
  run.generated = 12;
  run.refused = 1;
  run.faultPlan = {"kill-agent@10+2:0"};
  Accounting acc;
  acc.acknowledged = 11;
  acc.done = 9;
  acc.active = 2;
  StoreContents contents;
  const json report = buildReport(o, out, run, acc, contents);
  EXPECT_EQ(report["scenario"], "stage");
  EXPECT_EQ(report["sim_time_s"], 120.0);
  EXPECT_DOUBLE_EQ(report["real_time_factor"].get<double>(), 2.0);
  EXPECT_DOUBLE_EQ(report["throughput"]["done_per_sim_hour"].get<double>(), 270.0);
  EXPECT_EQ(report["tasks"]["generated"], 12);
  EXPECT_EQ(report["tasks"]["refused"], 1);
  EXPECT_EQ(report["safety"]["min_separation_m"]["robot_robot"], 0.61);
  EXPECT_EQ(report["agents"].size(), 1u);
  EXPECT_EQ(report["fault_plan"][0], "kill-agent@10+2:0");
  EXPECT_EQ(report["clock"], "wall");
  EXPECT_TRUE(report["kinematic_bound"].contains("error"));
  EXPECT_EQ(report["saturated"]["found"], false);
  EXPECT_EQ(report["store"]["backend"], "sqlite");

  const auto lines = reportLines(report, acc, "takeover p50 3.0 s");
  ASSERT_GE(lines.size(), 5u);
  EXPECT_EQ(lines[0],
            "11 acknowledged: 9 done, 0 failed, 0 cancelled, 2 still tracked; LOST 0, DUPLICATED 0");
  EXPECT_EQ(lines[1].rfind("120 s simulated in 60 s wall (2.00x)", 0), 0u) << lines[1];
  EXPECT_EQ(lines[2].rfind("agent-0 (wall): 3 robots, 9.90 cycles/s", 0), 0u) << lines[2];
  EXPECT_EQ(lines[3], "takeover p50 3.0 s");
  fs::remove_all(out);
}

TEST(LoadtestReport, AStoreThatCouldNotBeReadIsTheLastLine) {
  LoadtestOptions o;
  o.wallClock = true;
  const fs::path out = fs::temp_directory_path() / ("loadtest-report-db-" + std::to_string(::getpid()));
  fs::create_directories(out);
  StoreContents contents;
  contents.error = "fleet.db: no such table tasks";
  const json report = buildReport(o, out, RunOutcome{}, Accounting{}, contents);
  EXPECT_EQ(report["db_error"], "fleet.db: no such table tasks");
  const auto lines = reportLines(report, Accounting{}, "");
  EXPECT_EQ(lines.back(), "task database: fleet.db: no such table tasks");
  fs::remove_all(out);
}

}  // namespace
}  // namespace fleet::ctl
