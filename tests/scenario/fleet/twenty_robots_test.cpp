// The whole fleet in lockstep on the small warehouse: 20 robots, 8 people, 100 transport tasks
// posted through the WMS adapter by `fleetctl loadtest`. Safety is absolute (no contact of any
// kind); the fleet must not deadlock (tasks keep being delivered and every task ends), nearly all
// must be done, and nothing acknowledged may be lost or duplicated. The robots drive with the agent's
// default local planner (DWA with the risk term). The run stops when the last task is done (about
// 1700-2000 s simulated, 180-220 s wall); the time and tasks per hour are the figures of
// docs/benchmarks.md.

#include <gtest/gtest.h>
#include <sqlite3.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "test_process.hpp"

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

/// Every transition to `requeued` or `failed` with its robot and reason, for the log.
std::string failures(const fs::path& db) {
  std::string out;
  sqlite3* h = nullptr;
  if (sqlite3_open_v2(db.c_str(), &h, SQLITE_OPEN_READONLY, nullptr) == SQLITE_OK) {
    sqlite3_stmt* st = nullptr;
    if (sqlite3_prepare_v2(
            h,
            "SELECT stamp_ns, task_id, to_state, robot, reason FROM transitions WHERE to_state "
            "IN ('requeued', 'failed') ORDER BY seq",
            -1, &st, nullptr) == SQLITE_OK) {
      while (sqlite3_step(st) == SQLITE_ROW) {
        for (int c = 0; c < 5; ++c) {
          const auto* t = sqlite3_column_text(st, c);
          out += (c == 0 ? std::to_string(sqlite3_column_int64(st, 0) / 1'000'000'000) + " s"
                         : std::string(t != nullptr ? reinterpret_cast<const char*>(t) : "")) +
                 (c < 4 ? " | " : "\n");
        }
      }
    }
    sqlite3_finalize(st);
  }
  sqlite3_close(h);
  return out;
}

/// Simulated seconds at which tasks reached `done`, from the manager's database.
std::vector<double> doneTimes(const fs::path& db) {
  std::vector<double> t;
  sqlite3* h = nullptr;
  if (sqlite3_open_v2(db.c_str(), &h, SQLITE_OPEN_READONLY, nullptr) != SQLITE_OK) {
    sqlite3_close(h);
    return t;
  }
  sqlite3_stmt* st = nullptr;
  if (sqlite3_prepare_v2(h, "SELECT stamp_ns FROM transitions WHERE to_state = 'done' ORDER BY stamp_ns", -1,
                         &st, nullptr) == SQLITE_OK) {
    while (sqlite3_step(st) == SQLITE_ROW) {
      t.push_back(static_cast<double>(sqlite3_column_int64(st, 0)) * 1e-9);
    }
  }
  sqlite3_finalize(st);
  sqlite3_close(h);
  return t;
}

/// `fleetctl loadtest` on the 20-robot scenario: `tasks` at 12 per minute until all are done. A
/// lockstep step waits up to 5 s for every agent (the simulator's default is 1 s): in the
/// clean-clone check of c4bf61b one step took longer while the container images were built beside
/// this test, and the run counted a step timeout; a hung agent still counts one.
std::vector<std::string> loadtestArgs(const fs::path& out, int tasks, double durationS, int wallLimitS) {
  return {"loadtest",
          "--scenario",
          FLEET_SOURCE_DIR "/sim/scenarios/small_warehouse.json",
          "--tasks",
          std::to_string(tasks),
          "--rate",
          "12",
          "--until-done",
          "--duration",
          std::to_string(durationS),
          "--max-speed",
          "10",
          "--wall-limit",
          std::to_string(wallLimitS),
          "--step-timeout-ms",
          "5000",
          "--domain",
          std::to_string(fleet::test::uniqueDomain()),
          "--report-script",
          "",
          "--out",
          out.string()};
}

}  // namespace

TEST(FleetScenario, TwentyRobotsOneHundredTasksNoContactNoDeadlock) {
  const fs::path out = fs::temp_directory_path() / ("fleet_twenty_" + std::to_string(getpid()));
  fs::remove_all(out);
  fleet::test::ChildProcess run(FLEET_BINARY_DIR "/services/fleetctl/fleetctl",
                                loadtestArgs(out, 100, 2400.0, 450));
  ASSERT_EQ(run.wait(std::chrono::seconds(500)), 0) << "see " << out;
  const json r = json::parse(std::ifstream(out / "loadtest.json"));
  const auto& a = r["accounting"];
  EXPECT_EQ(r["wall_limited"], false) << "the machine could not keep up; see " << out;
  EXPECT_EQ(a["acknowledged"], 100);
  EXPECT_EQ(a["lost"], 0) << a.dump();
  EXPECT_EQ(a["duplicated"], 0) << a.dump();
  const auto& s = r["safety"];
  EXPECT_EQ(s["contacts"]["robot_robot"], 0) << s.dump();
  EXPECT_EQ(s["contacts"]["robot_human"], 0) << s.dump();
  EXPECT_EQ(s["contacts"]["robot_shelf"], 0) << s.dump();
  EXPECT_EQ(s["lockstep_step_timeouts"], 0) << s.dump();

  // No deadlock: from the first delivery to the end of the run, no 300 s without one.
  auto done = doneTimes(out / "fleet.db");
  ASSERT_FALSE(done.empty());
  const double end = r["sim_time_s"].get<double>();
  done.push_back(end);
  double longestGap = 0.0;
  for (std::size_t k = 1; k < done.size(); ++k) {
    longestGap = std::max(longestGap, done[k] - done[k - 1]);
  }
  EXPECT_LT(longestGap, 300.0) << "the fleet stopped delivering for " << longestGap << " s";
  // Every task finished (a deadlock leaves some queued or active) and done: a task whose robot gets
  // stuck is retried on another robot (up to three attempts). Until 2026-11-25 two neighbours in the
  // parking band could hold each other through all three (about 1 run in 10 ended 98 or 99); the
  // station axis and the rules for chains of waits (docs/algorithms.md, sixth round) ended that.
  // The retries and their reasons are printed below.
  EXPECT_EQ(a["done"].get<int>(), 100) << a.dump() << "\nrequeued and failed:\n"
                                       << failures(out / "fleet.db");
  std::cout << "requeued and failed:\n" << failures(out / "fleet.db");
  std::cout << "done " << a["done"] << " of 100 in " << end << " s simulated (" << r["wall_time_s"]
            << " s wall), failed " << a["failed"] << ", min separation robot-robot "
            << s["min_separation_m"]["robot_robot"] << " m, robot-human "
            << s["min_separation_m"]["robot_human"] << " m\n";
  if (!HasFailure()) {
    fs::remove_all(out);  // kept on failure: the logs and replay say why (a stall is read there)
  }
}

// Thesis 000 §3.2.3's risk stepping drives the fleet too (docs/benchmarks.md has its 100-task
// figures): 20 tasks done, no contact of any kind. About 40 s wall.
TEST(FleetScenario, TwentyRobotsDeliverWithRiskSteppingWithoutContact) {
  const fs::path out = fs::temp_directory_path() / ("fleet_twenty_rs_" + std::to_string(getpid()));
  fs::remove_all(out);
  auto args = loadtestArgs(out, 20, 900.0, 300);
  // In reserved traffic (the traffic manager plans, risk stepping drives each released base).
  args.insert(args.end(), {"--local-planner", "risk_stepping"});
  fleet::test::ChildProcess run(FLEET_BINARY_DIR "/services/fleetctl/fleetctl", args);
  ASSERT_EQ(run.wait(std::chrono::seconds(350)), 0) << "see " << out;
  const json r = json::parse(std::ifstream(out / "loadtest.json"));
  EXPECT_EQ(r["wall_limited"], false) << "the machine could not keep up; see " << out;
  EXPECT_EQ(r["accounting"]["done"].get<int>(), 20) << r["accounting"].dump() << "\n"
                                                    << failures(out / "fleet.db");
  const auto& s = r["safety"];
  EXPECT_EQ(s["contacts"]["robot_robot"], 0) << s.dump();
  EXPECT_EQ(s["contacts"]["robot_human"], 0) << s.dump();
  EXPECT_EQ(s["contacts"]["robot_shelf"], 0) << s.dump();
  // The planner itself drove: a planner that never moves a robot still finishes tasks, because the
  // agent's stall watch hands such robots to the path follower (a "planner recovery").
  int recoveries = 0;
  for (const auto& agent : r["agents"]) {
    recoveries += agent["conduct"]["planner_recoveries"].get<int>();
  }
  // 0-4 per 100-task run with risk_stepping (docs/benchmarks.md); a planner that never moves: 291.
  EXPECT_LE(recoveries, 5) << r["agents"].dump();
  if (!HasFailure()) {
    fs::remove_all(out);  // kept on failure: the logs and replay say why (a stall is read there)
  }
}
