// TC_CHANGE on the manager node (without DDS): a waiting task's priority and deadline changed,
// answered with the values in force, announced as a TaskEvent with `changed` set, in force at the
// next allocation, refused for a task that is not waiting, and durable across a restart.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <map>

#include "fleet_manager_node.hpp"

using namespace fleet;
using ::testing::HasSubstr;

namespace {

StationMap stations() {
  auto m = StationMap::fromJson(nlohmann::json::parse(R"({"stations": [
    {"name": "P-1", "x": 1, "y": 1, "theta": 0, "kinds": ["pickup"]},
    {"name": "D-1", "x": 5, "y": 1, "theta": 0, "kinds": ["dropoff"]}]})"));
  EXPECT_TRUE(m);
  return *m;
}

msg::Task transport(const std::string& id, std::int32_t priority, std::int64_t createdNs = 0) {
  msg::Task t;
  t.task_id = id;
  t.request_id = "req-" + id;
  t.kind = msg::TaskKind::Transport;
  t.pickup = "P-1";
  t.dropoff = "D-1";
  t.priority = priority;
  t.created_ns = createdNs;
  return t;
}

int gChange = 0;

msg::Task change(const std::string& id, std::optional<std::int32_t> priority,
                 std::optional<std::int64_t> deadline) {
  msg::Task t;
  t.task_id = id;
  t.request_id = "chg-" + std::to_string(++gChange);
  t.control = msg::TaskControl::Change;
  t.set_priority = priority.has_value();
  t.priority = priority.value_or(0);
  t.set_deadline = deadline.has_value();
  t.deadline_ns = deadline.value_or(0);
  return t;
}

msg::RobotState idle(const std::string& robot, std::int64_t t) {
  return {robot, t, {0, 1, 0}, {}, 0, 0, msg::RobotMode::Idle, 0.9f, "", 0.3f};
}

class TaskChange : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("fm_change_" + std::to_string(getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
    settings_.db = (dir_ / "fleet.db").string();
    settings_.stationsFile = "unused";
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::unique_ptr<manager::FleetManagerNode> open(std::int64_t now) {
    auto n = manager::FleetManagerNode::create(settings_, stations(), now);
    EXPECT_TRUE(n) << (n ? "" : n.error().message);
    return std::move(*n);
  }
  /// Robot r1 idle, tasks t1 and t2 submitted and one of them assigned: what that published.
  static manager::Outbox oneRobotTwoTasks(manager::FleetManagerNode& node) {
    manager::Outbox out;
    node.onRobotState(idle("r1", 1'000), 1'000);
    node.onRequests({transport("t1", 0), transport("t2", 0)}, 2'000, out);
    node.tick(3'000, out);
    return out;
  }
  /// The one ack in `out` to `req`.
  static msg::TaskAck ackOf(const manager::Outbox& out, const msg::Task& req) {
    for (const auto& a : out.acks) {
      if (a.request_id == req.request_id) {
        return a;
      }
    }
    ADD_FAILURE() << "no ack to " << req.request_id;
    return {};
  }
  std::filesystem::path dir_;
  manager::Settings settings_;
};

}  // namespace

TEST_F(TaskChange, AWaitingTasksNewPriorityDecidesTheNextAllocation) {
  auto node = open(0);
  manager::Outbox out;
  node->onRequests({transport("t1", 5), transport("t2", 0)}, 1'000, out);
  out = {};
  const auto up = change("t2", 50, 2'000'000'000);
  node->onRequests({up}, 2'000, out);
  const auto a = ackOf(out, up);
  EXPECT_EQ(a.result, msg::AckResult::Stored);
  EXPECT_EQ(a.state, msg::TaskState::Queued);
  const auto d = nlohmann::json::parse(a.detail);
  EXPECT_EQ(d["priority"], 50);
  EXPECT_EQ(d["deadline_ns"], 2'000'000'000);
  EXPECT_EQ(d["changed"], true);
  ASSERT_EQ(out.events.size(), 1u);
  EXPECT_EQ(out.events[0].task_id, "t2");
  EXPECT_EQ(out.events[0].state, msg::TaskState::Queued);
  EXPECT_TRUE(out.events[0].changed);
  EXPECT_EQ(out.events[0].priority, 50);
  EXPECT_EQ(out.events[0].deadline_ns, 2'000'000'000);
  EXPECT_EQ(out.events[0].seq, 2u) << "after the submission's";
  EXPECT_THAT(out.events[0].reason, HasSubstr("changed by request"));
  EXPECT_EQ(node->dispatcher().openTasks().at("t2").task.priority, 50);

  // Without the change t1 (priority 5) would go first to the only robot.
  node->onRobotState(idle("r1", 3'000), 3'000);
  out = {};
  node->tick(4'000, out);
  ASSERT_EQ(out.assignments.size(), 1u);
  EXPECT_EQ(out.assignments[0].task_id, "t2");
  EXPECT_EQ(out.assignments[0].priority, 50) << "the order carries the priority in force";
}

TEST_F(TaskChange, ARepeatedChangeIsAnsweredWithoutAnEventAndBadOnesAreRefused) {
  auto node = open(0);
  manager::Outbox out;
  node->onRequests({transport("t1", 0, 1'000'000)}, 1'000'000, out);
  out = {};
  const auto first = change("t1", 3, std::nullopt);
  const auto again = change("t1", 3, std::nullopt);
  const auto early = change("t1", std::nullopt, 999'999);  // before the task's created_ns
  const auto range = change("t1", 1001, std::nullopt);
  const auto nothing = change("t1", std::nullopt, std::nullopt);
  const auto unknown = change("zz", 1, std::nullopt);
  node->onRequests({first, again, early, range, nothing, unknown}, 2'000'000, out);
  EXPECT_EQ(ackOf(out, first).result, msg::AckResult::Stored);
  EXPECT_EQ(ackOf(out, again).result, msg::AckResult::Stored) << "idempotent";
  EXPECT_EQ(nlohmann::json::parse(ackOf(out, again).detail)["changed"], false);
  EXPECT_EQ(out.events.size(), 1u) << "one change, one event";
  for (const auto* req : {&early, &range, &nothing}) {
    const auto a = ackOf(out, *req);
    EXPECT_EQ(a.result, msg::AckResult::Invalid) << req->request_id;
    const auto fields = nlohmann::json::parse(a.detail, nullptr, false);
    ASSERT_TRUE(fields.is_array()) << a.detail;
    ASSERT_FALSE(fields.empty());
    EXPECT_TRUE(fields[0].contains("path"));
  }
  EXPECT_EQ(nlohmann::json::parse(ackOf(out, early).detail)[0]["path"], "deadline_ns");
  EXPECT_EQ(nlohmann::json::parse(ackOf(out, range).detail)[0]["path"], "priority");
  EXPECT_EQ(ackOf(out, unknown).result, msg::AckResult::NotFound);
  EXPECT_EQ(node->dispatcher().openTasks().at("t1").task.priority, 3);
}

TEST_F(TaskChange, AnAssignedOrFinishedTaskIsRefusedNamingItsState) {
  auto node = open(0);
  manager::Outbox out;
  node->onRequests({transport("t1", 0), transport("t2", 0)}, 1'000, out);
  msg::Task cancel;
  cancel.task_id = "t2";
  cancel.request_id = "cancel-t2";
  cancel.cancel = true;
  node->onRequests({cancel}, 1'500, out);
  node->onRobotState(idle("r1", 2'000), 2'000);
  node->tick(3'000, out);
  ASSERT_EQ(node->dispatcher().openTasks().at("t1").state, TaskState::Assigned);
  out = {};
  const auto active = change("t1", 9, std::nullopt);
  const auto finished = change("t2", 9, std::nullopt);
  node->onRequests({active, finished}, 4'000, out);
  const auto a = ackOf(out, active);
  EXPECT_EQ(a.result, msg::AckResult::Refused);
  EXPECT_EQ(a.state, msg::TaskState::Assigned);
  EXPECT_THAT(a.detail, HasSubstr("is assigned"));
  const auto f = ackOf(out, finished);
  EXPECT_EQ(f.result, msg::AckResult::Refused);
  EXPECT_EQ(f.state, msg::TaskState::Cancelled);
  EXPECT_THAT(f.detail, HasSubstr("cancelled"));
  EXPECT_TRUE(out.events.empty());
  EXPECT_TRUE(out.assignments.empty());
}

TEST_F(TaskChange, AChangeOutlivesARestartAndTheEventsCountGoesOn) {
  {
    auto node = open(0);
    manager::Outbox out;
    node->onRequests({transport("t1", 0)}, 1'000, out);
    node->onRequests({change("t1", 7, 5'000'000'000)}, 2'000, out);
  }
  auto node = open(10'000);
  const auto& r = node->dispatcher().openTasks().at("t1");
  EXPECT_EQ(r.task.priority, 7);
  EXPECT_EQ(r.task.deadlineNs, 5'000'000'000);
  ASSERT_EQ(node->recovered().events.size(), 1u);
  EXPECT_EQ(node->recovered().events[0].seq, 2u)
      << "the revision counts the change: the next event does not repeat the change's seq";
  // The WMS retries its original submission: the same request, the change stays.
  manager::Outbox out;
  auto retry = transport("t1", 0);
  retry.request_id = "retry";
  node->onRequests({retry}, 20'000, out);
  EXPECT_EQ(ackOf(out, retry).result, msg::AckResult::Duplicate);
  EXPECT_EQ(node->dispatcher().openTasks().at("t1").task.priority, 7);
}

TEST_F(TaskChange, TheEventsOnTheWireCarryTheTasksEta) {
  // The dispatcher's estimate (TaskEta) reaches the TaskEvent the adapter shows the WMS: a task
  // assigned to the one robot is due after now, and the task waiting behind it later still.
  auto node = open(0);
  const auto out = oneRobotTwoTasks(*node);
  std::map<std::string, std::int64_t> eta;
  for (const auto& e : out.events) {
    eta[e.task_id] = e.eta_ns;  // the newest event of each task
  }
  ASSERT_EQ(out.assignments.size(), 1u);
  const auto& first = out.assignments[0].task_id;
  const auto& second = first == "t1" ? std::string("t2") : std::string("t1");
  EXPECT_GT(eta[first], 3'000) << "an assigned task is due after now";
  EXPECT_GT(eta[second], eta[first]) << "the waiting one after the robot's current task";
}

TEST_F(TaskChange, TheLeaseEpochIsStampedOnEveryAssignmentAndEventFromThenOn) {
  {
    auto node = open(0);
    const auto out = oneRobotTwoTasks(*node);
    ASSERT_FALSE(out.assignments.empty());
    for (const auto& e : out.events) {
      EXPECT_EQ(e.epoch, 0) << "no lease: epoch 0";
    }
  }
  // A standby that takes the lease (epoch 7) rebuilds from the store: what it re-publishes and
  // everything after carries its epoch.
  auto node = open(10'000);
  node->setEpoch(7);
  ASSERT_FALSE(node->recovered().events.empty());
  ASSERT_FALSE(node->recovered().assignments.empty());
  for (const auto& e : node->recovered().events) {
    EXPECT_EQ(e.epoch, 7) << e.task_id;
  }
  for (const auto& a : node->recovered().assignments) {
    EXPECT_EQ(a.epoch, 7) << a.robot_id;
  }
  manager::Outbox out;
  const auto cancel = [] {
    msg::Task t;
    t.task_id = "t1";
    t.request_id = "cancel-t1";
    t.cancel = true;
    return t;
  }();
  node->onRobotState(idle("r1", 11'000), 11'000);
  node->onRequests({cancel}, 12'000, out);
  node->tick(13'000, out);
  ASSERT_FALSE(out.events.empty());
  for (const auto& e : out.events) {
    EXPECT_EQ(e.epoch, 7) << e.task_id;
  }
  for (const auto& a : out.assignments) {
    EXPECT_EQ(a.epoch, 7) << a.robot_id;
  }
}

// A pause is an event of the task's without a transition: the stored revision counts it, so a
// restarted manager numbers the next event after it. Before (2026-12-03) the revision counted only
// transitions and changes: after a restart the resume repeated the pause's seq and the adapter's
// event log, which keeps one event per (task, seq), dropped it — the WMS never heard "resumed".
TEST_F(TaskChange, APauseOutlivesARestartAndTheNextEventIsNumberedAfterIt) {
  std::uint32_t pausedSeq = 0;
  {
    auto node = open(0);
    manager::Outbox out;
    node->onRequests({transport("t1", 0)}, 1'000, out);
    msg::Task pause;
    pause.task_id = "t1";
    pause.request_id = "pause-1";
    pause.control = msg::TaskControl::Pause;
    out = {};
    node->onRequests({pause}, 2'000, out);
    ASSERT_FALSE(out.events.empty());
    pausedSeq = out.events.back().seq;
    EXPECT_EQ(pausedSeq, 2U) << "queued (1), paused (2)";
  }
  auto node = open(10'000);
  ASSERT_EQ(node->recovered().events.size(), 1U);
  EXPECT_EQ(node->recovered().events[0].seq, pausedSeq) << "the announcement repeats the last event's seq";
  msg::Task resume;
  resume.task_id = "t1";
  resume.request_id = "resume-1";
  resume.control = msg::TaskControl::Resume;
  manager::Outbox out;
  node->onRequests({resume}, 20'000, out);
  ASSERT_FALSE(out.events.empty());
  EXPECT_EQ(out.events.back().seq, pausedSeq + 1) << "numbered after the pause, not again as it";
}
