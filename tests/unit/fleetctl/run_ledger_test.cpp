// The robot-time and station ledgers of a run (run_ledger.hpp).

#include "run_ledger.hpp"

#include <map>

#include <gtest/gtest.h>

#include <random>

namespace fleet::ctl {
namespace {

RobotSample at(Vec2 p, std::string mode, std::string task = {}, std::string activity = {}) {
  return {p, false, std::move(mode), std::move(task), std::move(activity)};
}

// Property: over random steps of random states, every robot's ledger adds up to 100 % of its run
// time (the span from the first step to the last), whatever it said or did not say.
TEST(RunLedger, EveryRobotsTimeAddsUpToTheRunWhateverItDid) {
  std::mt19937 rng(11);
  const char* modes[] = {"idle", "moving", "waiting", "loading", "charging", "blocked", "fault", "???"};
  const char* acts[] = {"", "unset", "driving", "held_by_person", "dwelling", "nonsense", "faulted"};
  for (int trial = 0; trial < 20; ++trial) {
    const std::size_t n = 1 + rng() % 6;
    std::vector<std::string> ids;
    for (std::size_t i = 0; i < n; ++i) {
      ids.push_back("r" + std::to_string(i));
    }
    RunLedger l(ids, {{"A", {0, 0}}, {"B", {5, 0}}}, {{"t1", {"A", "B"}}});
    double t = 0.0;
    for (int k = 0; k < 200; ++k) {
      std::vector<RobotSample> s;
      for (std::size_t i = 0; i < n; ++i) {
        s.push_back({{std::uniform_real_distribution<double>(-1, 6)(rng), 0.0},
                     rng() % 5 == 0,
                     modes[rng() % 8],
                     rng() % 2 ? "t1" : "",
                     acts[rng() % 7]});
      }
      l.step(t, s);
      t += std::uniform_real_distribution<double>(0.01, 1.0)(rng);
    }
    const auto j = l.robotTimeJson();
    for (std::size_t i = 0; i < n; ++i) {
      double sum = 0.0;
      for (const auto& [cat, share] : j["per_robot"][ids[i]]["share"].items()) {
        sum += share.get<double>();
      }
      EXPECT_NEAR(sum, 1.0, 0.006) << "nine shares rounded to 0.001";
      EXPECT_NEAR(l.robot(i).total(), j["per_robot"][ids[i]]["total_s"].get<double>(), 1e-3);
    }
  }
}

TEST(RunLedger, SaidActivityWinsAndTheModeStandsInWhenUnset) {
  RunLedger l({"r"}, {}, {});
  // Each step's state holds until the next: 2 s held by a person (said), 3 s driving (its mode),
  // 1 s no task (idle without one), 4 s waiting on another robot (waiting, activity unset).
  l.step(0.0, {at({0, 0}, "moving", "t", "held_by_person")});
  l.step(2.0, {at({0, 0}, "moving", "t")});
  l.step(5.0, {at({0, 0}, "idle")});
  l.step(6.0, {at({0, 0}, "waiting", "t", "unset")});
  l.step(10.0, {at({0, 0}, "idle")});
  EXPECT_DOUBLE_EQ(l.robot(0).seconds(RobotActivity::HeldByPerson), 2.0);
  EXPECT_DOUBLE_EQ(l.robot(0).seconds(RobotActivity::Driving), 3.0);
  EXPECT_DOUBLE_EQ(l.robot(0).seconds(RobotActivity::NoTask), 1.0);
  EXPECT_DOUBLE_EQ(l.robot(0).seconds(RobotActivity::WaitingOnRobot), 4.0);
  EXPECT_EQ(l.robotTimeJson()["source"], "activity and mode");
  l.step(9.0, {at({0, 0}, "idle")});  // back in time: skipped
  l.step(11.0, {});                   // wrong count: skipped
  EXPECT_EQ(l.skippedSteps(), 2u);
}

// Two robots for station A: r0 docks at 1 s, leaves at 5 s while r1 waits (its goal is A); r1
// docks at 7 s. One cycle of 6 s, two visits, A docked 4 + 3 s of 10.
TEST(RunLedger, StationVisitsUtilisationQueueAndCycle) {
  RunLedger l({"r0", "r1"}, {{"A", {0, 0}}, {"B", {9, 0}}}, {{"t0", {"A", "B"}}, {"t1", {"A", "B"}}});
  const Vec2 far{3, 0}, dock{0, 0}, near{1, 0};
  l.step(0.0, {at(far, "moving", "t0"), at(far, "moving", "t1")});
  l.step(1.0, {at(dock, "loading", "t0"), at(near, "waiting", "t1")});
  l.step(5.0, {at(near, "moving", "t0"), at(near, "waiting", "t1")});
  l.step(7.0, {at(far, "moving", "t0"), at(dock, "loading", "t1")});
  l.step(10.0, {at(far, "moving", "t0"), at(near, "moving", "t1")});
  const auto s = l.stationsJson();
  ASSERT_EQ(s.size(), 2u) << s.dump();  // A visited, B the goal of both after their pickup
  EXPECT_EQ(s[0]["name"], "A");
  EXPECT_EQ(s[0]["visits"], 2);
  EXPECT_DOUBLE_EQ(s[0]["utilisation"].get<double>(), 0.7);
  EXPECT_EQ(s[0]["cycles"], 1);
  EXPECT_DOUBLE_EQ(s[0]["cycle_p50_s"].get<double>(), 6.0);
  EXPECT_DOUBLE_EQ(s[0]["occupancy_p50_s"].get<double>(), 3.0);
  // Queue at A: r0 before docking (1 s), r1 until it docks (7 s): 8 robot-s over 10 s; at most 2.
  EXPECT_DOUBLE_EQ(s[0]["queue_mean"].get<double>(), 0.8);
  EXPECT_EQ(s[0]["queue_max"], 2);
  EXPECT_EQ(s[1]["name"], "B");
  EXPECT_EQ(s[1]["visits"], 0);
}

// A dock cycle is the station's own only when the next robot stood in its line as the last one
// left: a robot still driving from afar then is not counted, one within the line's reach is.
TEST(RunLedger, ADockCycleCountsOnlyWhenTheNextRobotStoodInTheLine) {
  const std::map<std::string, LedgerTask> tasks{{"t0", {"A", "B"}}, {"t1", {"A", "B"}}};
  const Vec2 far{3, 0}, dock{0, 0}, near{1, 0};
  for (const bool nextNear : {false, true}) {
    SCOPED_TRACE(nextNear ? "next in line" : "next far");
    RunLedger l({"r0", "r1"}, {{"A", {0, 0}, 2.0}, {"B", {9, 0}, 2.0}}, tasks);
    const Vec2 next = nextNear ? near : far;
    l.step(0.0, {at(far, "moving", "t0"), at(far, "moving", "t1")});
    l.step(1.0, {at(dock, "loading", "t0"), at(next, "moving", "t1")});
    l.step(5.0, {at(near, "moving", "t0"), at(next, "moving", "t1")});  // r0 leaves
    l.step(7.0, {at(far, "moving", "t0"), at(dock, "loading", "t1")});
    const auto s = l.stationsJson();
    ASSERT_FALSE(s.empty());
    EXPECT_EQ(s[0]["name"], "A");
    EXPECT_EQ(s[0]["visits"], 2);
    EXPECT_EQ(s[0]["cycles"], nextNear ? 1 : 0) << s.dump();
    EXPECT_EQ(s[0]["queue_max"], 2);  // the queue counts robots bound for A wherever they are
  }
}

// Docking: from the robot's last step at the station's entry to its arrival at the dock, against
// the roadmap's time for that leg; a robot waiting at the entry is not docking yet, and a visit
// without a step at the entry (the robot came another way) is not measured.
TEST(RunLedger, DockingIsTimedFromLeavingTheEntryAgainstTheLegsModelledTime) {
  LedgerStation a{"A", {0, 0}};
  a.hasEntry = true;
  a.entry = {1, 0};
  a.dockModelS = 1.5;
  RunLedger l({"r0", "r1"}, {a, {"B", {9, 0}}}, {{"t0", {"A", "B"}}, {"t1", {"A", "B"}}});
  const Vec2 far{3, 0}, dock{0, 0}, entry{1, 0}, between{0.5, 0};
  l.step(0.0, {at(entry, "waiting", "t0"), at(far, "moving", "t1")});
  l.step(4.0, {at(entry, "moving", "t0"), at(far, "moving", "t1")});  // waited 4 s at the entry
  l.step(5.0, {at(between, "moving", "t0"), at(far, "moving", "t1")});
  l.step(5.5, {at(dock, "loading", "t0"), at(far, "moving", "t1")});  // 1.5 s after leaving it
  l.step(9.0, {at(far, "moving", "t0"), at(entry, "moving", "t1")});
  l.step(14.0, {at(far, "moving", "t0"), at(dock, "loading", "t1")});  // 5 s: over 1.5 + 2
  const auto s = l.stationsJson();
  ASSERT_FALSE(s.empty());
  EXPECT_EQ(s[0]["name"], "A");
  EXPECT_EQ(s[0]["dockings"], 2);
  EXPECT_DOUBLE_EQ(s[0]["dock_model_s"].get<double>(), 1.5);
  EXPECT_DOUBLE_EQ(s[0]["docking_max_s"].get<double>(), 5.0);
  EXPECT_EQ(s[0]["dockings_over_model"], 1);
  const auto lines = ledgerLines(l.robotTimeJson(), s);
  ASSERT_EQ(lines.size(), 3u);
  EXPECT_NE(lines[2].find("1 of 2 dockings within"), std::string::npos) << lines[2];
  // B has no entry: no docking figures.
  for (const auto& st : s) {
    if (st["name"] == "B") {
      EXPECT_FALSE(st.contains("dockings"));
    }
  }
}

}  // namespace
}  // namespace fleet::ctl
