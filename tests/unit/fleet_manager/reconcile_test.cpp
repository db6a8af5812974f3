// The manager reconciles each robot's reported task (RobotState.task_id) with the store: a robot
// that dropped its task without a report (an agent refusing an order cleared its current task and
// then reported idle, while the manager kept the task en_route until an unrelated lease loss)
// gets the task requeued after reconcile_s.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>

#include "fleet_manager_node.hpp"

using namespace fleet;
using ::testing::HasSubstr;

namespace {
constexpr std::int64_t kS = 1'000'000'000;

StationMap stations() {
  auto m = StationMap::fromJson(nlohmann::json::parse(R"({"stations": [
    {"name": "P-1", "x": 1, "y": 1, "theta": 0, "kinds": ["pickup"]},
    {"name": "D-1", "x": 5, "y": 1, "theta": 0, "kinds": ["dropoff"]},
    {"name": "C-1", "x": 0, "y": 0, "theta": 0, "kinds": ["charging", "parking"]}]})"));
  EXPECT_TRUE(m);
  return *m;
}

msg::Task transport(const std::string& id) {
  msg::Task t;
  t.task_id = id;
  t.request_id = "req-" + id;
  t.kind = msg::TaskKind::Transport;
  t.pickup = "P-1";
  t.dropoff = "D-1";
  return t;
}

msg::RobotState state(const std::string& robot, double x, const std::string& task, std::int64_t t) {
  return {robot, t,    {x, 1, 0}, {}, 0, 0, task.empty() ? msg::RobotMode::Idle : msg::RobotMode::Moving,
          0.9f,  task, 0.3f};
}

class Reconcile : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("fm_reconcile_" + std::to_string(getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
    settings_.db = (dir_ / "fleet.db").string();
    settings_.stationsFile = "unused";
    settings_.leaseS = 2.0;
    settings_.reconcileS = 5.0;
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::unique_ptr<manager::FleetManagerNode> open(std::int64_t now) {
    auto n = manager::FleetManagerNode::create(settings_, stations(), now);
    EXPECT_TRUE(n) << (n ? "" : n.error().message);
    return std::move(*n);
  }
  /// r1 alone takes t1 at 1 s and reports it en_route; returns the order.
  msg::TaskAssignment assignT1(manager::FleetManagerNode& node) {
    manager::Outbox out;
    node.onRequests({transport("t1")}, 0, out);
    node.onRobotState(state("r1", 0, "", kS), kS);
    node.tick(kS, out);
    EXPECT_EQ(out.assignments.size(), 1u);
    const auto a = out.assignments.empty() ? msg::TaskAssignment{} : out.assignments[0];
    EXPECT_EQ(a.robot_id, "r1");
    node.onStatus({"r1", "t1", a.revision, msg::TaskState::EnRoute, 0.1f, "", kS + 1}, kS + 1, out);
    return a;
  }
  /// States of the robots every 0.2 s (r1 reporting `r1Task`, r2 idle when `withR2`) and ticks,
  /// from `from` to before `to`; everything they produced.
  manager::Outbox drive(manager::FleetManagerNode& node, std::int64_t from, std::int64_t to,
                        const std::string& r1Task, bool withR2 = false) {
    manager::Outbox out;
    for (std::int64_t t = from; t < to; t += kS / 5) {
      node.onRobotState(state("r1", 0, r1Task, t), t);
      if (withR2) {
        node.onRobotState(state("r2", 4, "", t), t);
      }
      node.tick(t, out);
    }
    return out;
  }
  static int count(const manager::Outbox& out, const std::string& task, msg::TaskState s) {
    int n = 0;
    for (const auto& e : out.events) {
      n += e.task_id == task && e.state == s ? 1 : 0;
    }
    return n;
  }
  std::filesystem::path dir_;
  manager::Settings settings_;
};
}  // namespace

TEST_F(Reconcile, ATaskItsRobotDroppedSilentlyIsRequeuedAfterTheGraceAndDoneOnce) {
  auto node = open(0);
  assignT1(*node);
  // From 2 s on r1 reports idle with no task (it dropped t1 without a word); it stays alive, so
  // its lease never expires. r2 is idle beside it.
  auto before = drive(*node, 2 * kS, 7 * kS, "", true);
  EXPECT_EQ(count(before, "t1", msg::TaskState::Requeued), 0) << "within the grace";
  EXPECT_TRUE(before.reconciled.empty());
  EXPECT_EQ(node->dispatcher().openTasks().at("t1").state, TaskState::EnRoute);

  auto after = drive(*node, 7 * kS, 8 * kS, "", true);
  ASSERT_EQ(count(after, "t1", msg::TaskState::Requeued), 1);
  for (const auto& e : after.events) {
    if (e.state == msg::TaskState::Requeued) {
      EXPECT_THAT(e.reason, HasSubstr("robot r1 reported no task for 5.0 s"));
      EXPECT_THAT(e.reason, HasSubstr("en_route"));
    }
  }
  ASSERT_EQ(after.reconciled.size(), 1u);
  const auto& note = after.reconciled[0];
  EXPECT_EQ(note.action, "requeued");
  EXPECT_EQ(note.robot, "r1");
  EXPECT_EQ(note.task, "t1");
  EXPECT_EQ(note.reported, "");
  EXPECT_EQ(note.sinceNs, 2 * kS);
  EXPECT_THAT(note.message,
              HasSubstr("task t1 requeued: robot r1 has reported no task (since 2000000000 ns"));
  // Reassigned in the same tick, to the other idle robot, once.
  ASSERT_EQ(after.assignments.size(), 1u);
  const auto again = after.assignments[0];
  EXPECT_EQ(again.robot_id, "r2");
  EXPECT_EQ(again.task_id, "t1");
  EXPECT_EQ(node->metrics().reconciledRequeued, 1);
  EXPECT_EQ(node->metricsJson()["reconciled"]["requeued"], 1);

  manager::Outbox out;
  node->onStatus({"r2", "t1", again.revision, msg::TaskState::Done, 1.0f, "", 8 * kS}, 8 * kS, out);
  auto rest = drive(*node, 8 * kS, 20 * kS, "", true);
  EXPECT_TRUE(rest.assignments.empty());
  EXPECT_TRUE(rest.reconciled.empty());
  EXPECT_TRUE(node->dispatcher().openTasks().empty());
  const auto& c = node->dispatcher().counters();
  EXPECT_EQ(c.done, 1);
  EXPECT_EQ(c.requeued, 1);
  EXPECT_EQ(c.assigned, 2);
  EXPECT_EQ(c.failed, 0);
}

TEST_F(Reconcile, AloneTheRobotThatDroppedItTakesTheTaskAgain) {
  auto node = open(0);
  const auto first = assignT1(*node);
  auto out = drive(*node, 2 * kS, 8 * kS, "");
  ASSERT_EQ(count(out, "t1", msg::TaskState::Requeued), 1);
  ASSERT_EQ(out.assignments.size(), 1u);
  EXPECT_EQ(out.assignments[0].robot_id, "r1");
  EXPECT_EQ(out.assignments[0].task_id, "t1");
  EXPECT_GT(out.assignments[0].revision, first.revision);
  // It reports t1 from now on: nothing more happens.
  auto rest = drive(*node, 8 * kS, 30 * kS, "t1");
  EXPECT_TRUE(rest.events.empty());
  EXPECT_TRUE(rest.reconciled.empty());
}

TEST_F(Reconcile, ARobotSlowToReportItsNewTaskWithinTheGraceKeepsIt) {
  auto node = open(0);
  assignT1(*node);
  // The order takes 4.5 s to show in r1's states (a slow link, a busy agent).
  auto out = drive(*node, kS + kS / 5, 5 * kS + kS / 2, "");
  auto rest = drive(*node, 5 * kS + kS / 2, 30 * kS, "t1");
  EXPECT_EQ(count(out, "t1", msg::TaskState::Requeued) + count(rest, "t1", msg::TaskState::Requeued), 0);
  EXPECT_TRUE(out.reconciled.empty());
  EXPECT_TRUE(rest.reconciled.empty());
  EXPECT_EQ(node->dispatcher().openTasks().at("t1").robotId, "r1");
  EXPECT_EQ(node->metrics().reconciledRequeued, 0);
}

TEST_F(Reconcile, ADoneReportRacingAnIdleStateWins) {
  auto node = open(0);
  const auto a = assignT1(*node);
  drive(*node, 2 * kS, 10 * kS, "t1");
  // r1 finishes: its next state (idle, no task) arrives before its TaskStatus done.
  manager::Outbox out;
  node->onRobotState(state("r1", 0, "", 10 * kS), 10 * kS);
  node->onStatus({"r1", "t1", a.revision, msg::TaskState::Done, 1.0f, "", 10 * kS + 1}, 10 * kS + 1, out);
  auto rest = drive(*node, 10 * kS + kS / 5, 30 * kS, "");
  EXPECT_EQ(count(rest, "t1", msg::TaskState::Requeued), 0);
  EXPECT_TRUE(rest.reconciled.empty());
  EXPECT_EQ(node->dispatcher().counters().done, 1);
  EXPECT_EQ(node->dispatcher().counters().requeued, 0);
}

TEST_F(Reconcile, AfterARestartTheGraceStartsFresh) {
  {
    auto node = open(0);
    assignT1(*node);
    drive(*node, 2 * kS, 6 * kS, "");  // 4 s of no task: within the grace when the manager stops
  }
  auto node = open(6 * kS);
  ASSERT_EQ(node->recovered().assignments.size(), 1u);
  EXPECT_EQ(node->recovered().assignments[0].task_id, "t1");
  auto within = drive(*node, 6 * kS, 11 * kS, "");
  EXPECT_EQ(count(within, "t1", msg::TaskState::Requeued), 0) << "the 4 s before the restart do not count";
  auto after = drive(*node, 11 * kS, 12 * kS, "");
  EXPECT_EQ(count(after, "t1", msg::TaskState::Requeued), 1);
  ASSERT_EQ(after.reconciled.size(), 1u);
  EXPECT_EQ(after.reconciled[0].sinceNs, 6 * kS);
}

TEST_F(Reconcile, AfterARestartARobotReportingItsTaskResumesIt) {
  {
    auto node = open(0);
    assignT1(*node);
  }
  auto node = open(2 * kS);
  auto out = drive(*node, 2 * kS, 30 * kS, "t1");
  EXPECT_TRUE(out.events.empty());
  EXPECT_TRUE(out.reconciled.empty());
  EXPECT_EQ(node->dispatcher().openTasks().at("t1").state, TaskState::EnRoute);
}

TEST_F(Reconcile, AReportOfAFinishedTaskIsLoggedAndCountedOnce) {
  auto node = open(0);
  const auto a = assignT1(*node);
  manager::Outbox out;
  node->onStatus({"r1", "t1", a.revision, msg::TaskState::Done, 1.0f, "", 2 * kS}, 2 * kS, out);
  // r1's states keep showing t1 (its agent did not let go): the manager has it carry nothing.
  auto reports = drive(*node, 2 * kS, 20 * kS, "t1");
  ASSERT_EQ(reports.reconciled.size(), 1u);
  EXPECT_EQ(reports.reconciled[0].action, "stale_report");
  EXPECT_EQ(reports.reconciled[0].robot, "r1");
  EXPECT_EQ(reports.reconciled[0].task, "t1");
  EXPECT_THAT(reports.reconciled[0].message, HasSubstr("which is already done"));
  EXPECT_TRUE(reports.events.empty());
  EXPECT_EQ(node->metrics().reconciledStale, 1);
  EXPECT_EQ(node->metricsJson()["reconciled"]["stale_report"], 1);
}

TEST_F(Reconcile, AReportOfAnotherRobotsTaskIsLoggedAndTheRobotsOwnTaskRequeued) {
  auto node = open(0);
  manager::Outbox out;
  node->onRequests({transport("t1"), transport("t2")}, 0, out);
  node->onRobotState(state("r1", 0, "", kS), kS);
  node->onRobotState(state("r2", 4, "", kS), kS);
  out = {};
  node->tick(kS, out);
  ASSERT_EQ(out.assignments.size(), 2u);
  const std::string r1Task = node->dispatcher().robots().find("r1")->taskId;
  const std::string r2Task = node->dispatcher().robots().find("r2")->taskId;
  // r1 reports r2's task (a stale order replayed): its own is missing, r2's is not its.
  manager::Outbox got;
  for (std::int64_t t = kS + kS / 5; t < 7 * kS; t += kS / 5) {
    node->onRobotState(state("r1", 0, r2Task, t), t);
    node->onRobotState(state("r2", 4, r2Task, t), t);
    node->tick(t, got);
  }
  EXPECT_EQ(count(got, r1Task, msg::TaskState::Requeued), 1);
  EXPECT_EQ(count(got, r2Task, msg::TaskState::Requeued), 0);
  ASSERT_EQ(got.reconciled.size(), 2u);
  EXPECT_EQ(got.reconciled[0].action, "requeued");
  EXPECT_EQ(got.reconciled[0].reported, r2Task);
  EXPECT_EQ(got.reconciled[1].action, "stale_report");
  EXPECT_THAT(got.reconciled[1].message, HasSubstr("held by robot r2"));
  EXPECT_EQ(node->dispatcher().openTasks().at(r2Task).robotId, "r2");
}

TEST_F(Reconcile, ZeroTurnsItOff) {
  settings_.reconcileS = 0;
  auto node = open(0);
  assignT1(*node);
  auto out = drive(*node, 2 * kS, 30 * kS, "");
  EXPECT_TRUE(out.events.empty());
  EXPECT_TRUE(out.reconciled.empty());
}

TEST(ReconcileSettings, ReconcileSecondsDefaultsToFiveAndRefusesNegatives) {
  auto defaults = Config::fromText(R"({"stations": "s.json"})", "manager.json");
  EXPECT_DOUBLE_EQ(manager::readSettings(defaults).reconcileS, 5.0);
  auto off = Config::fromText(R"({"stations": "s.json", "reconcile_s": 0})", "manager.json");
  EXPECT_DOUBLE_EQ(manager::readSettings(off).reconcileS, 0.0);
  EXPECT_TRUE(off.ok());
  auto bad = Config::fromText(R"({"stations": "s.json", "reconcile_s": -1})", "manager.json");
  manager::readSettings(bad);
  ASSERT_FALSE(bad.ok());
  EXPECT_THAT(bad.problems()[0], HasSubstr("reconcile_s"));
}
