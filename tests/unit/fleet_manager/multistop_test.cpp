// Multi-stop tasks in the fleet manager: one goal a step (with the load ids), every stop counted
// as a station visit, travel cost to the first stop, and the stop the robot reports on the events.

#include <gtest/gtest.h>

#include <filesystem>

#include "fleet/fleet/task_wire.hpp"
#include "fleet_manager_node.hpp"

using namespace fleet;

namespace {

StationMap multistopStations() {
  auto m = StationMap::fromJson(nlohmann::json::parse(R"({"stations": [
    {"name": "P-1", "x": 1, "y": 1, "theta": 0, "kinds": ["pickup"]},
    {"name": "D-1", "x": 5, "y": 1, "theta": 0, "kinds": ["dropoff"]},
    {"name": "X", "x": 9, "y": 1, "theta": 0, "kinds": ["parking"]}]})"));
  EXPECT_TRUE(m);
  return *m;
}

msg::Task wireTask(const std::string& body, const std::string& requestId) {
  const auto t = parseTask(nlohmann::json::parse(body));
  EXPECT_TRUE(t) << body;
  return toWire(t ? *t : Task{}, requestId, 1);
}

constexpr const char* kThreeStops = R"({"id": "m-1", "kind": "multistop", "steps": [
    {"action": "pick", "station": "P-1", "load_id": "L-1", "duration_ns": 2000000000},
    {"action": "drop", "station": "D-1", "load_id": "L-1"},
    {"action": "wait", "duration_ns": 1000000000}]})";

msg::RobotState robotAt(const std::string& id, double x, std::int64_t now) {
  return {id, now, {x, 1, 0}, {}, 0, 0, msg::RobotMode::Idle, 0.9f, "", 0.3f};
}

class Multistop : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("fm_multistop_" + std::to_string(getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
    settings_.db = (dir_ / "fleet.db").string();
    settings_.stationsFile = "unused";
    settings_.travelCost = "straight";
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::unique_ptr<manager::FleetManagerNode> open() {
    auto n = manager::FleetManagerNode::create(settings_, multistopStations(), 1'000);
    EXPECT_TRUE(n) << (n ? "" : n.error().message);
    return std::move(*n);
  }
  std::filesystem::path dir_;
  manager::Settings settings_;
};

}  // namespace

TEST_F(Multistop, EachStepIsAGoalWithItsActionLoadAndDwell) {
  auto node = open();
  manager::Outbox out;
  node->onRequests({wireTask(kThreeStops, "q1")}, 1'000'000, out);
  ASSERT_EQ(out.acks.size(), 1u);
  EXPECT_EQ(out.acks[0].result, msg::AckResult::Stored) << out.acks[0].detail;
  node->onRobotState(robotAt("r1", 0, 1'000'000), 1'000'000);
  out = {};
  node->tick(2'000'000, out);
  ASSERT_EQ(out.assignments.size(), 1u);
  const auto a = out.assignments[0];
  ASSERT_EQ(a.goals.size(), 3u);
  EXPECT_EQ(a.goals[0].station, "P-1");
  EXPECT_EQ(a.goals[0].action, msg::GoalAction::Load);
  EXPECT_EQ(a.goals[0].load_id, "L-1");
  EXPECT_DOUBLE_EQ(a.goals[0].duration_s, 2.0);
  EXPECT_EQ(a.goals[1].station, "D-1");
  EXPECT_EQ(a.goals[1].action, msg::GoalAction::Unload);
  EXPECT_EQ(a.goals[1].load_id, "L-1");
  // The wait without a station waits where the drop ended.
  EXPECT_EQ(a.goals[2].station, "D-1");
  EXPECT_DOUBLE_EQ(a.goals[2].pose.x, 5.0);
  EXPECT_EQ(a.goals[2].action, msg::GoalAction::None);
  EXPECT_DOUBLE_EQ(a.goals[2].duration_s, 1.0);
  EXPECT_TRUE(a.goals[2].load_id.empty());
}

TEST_F(Multistop, TheStopTheRobotReportsIsOnTheTasksEventsAndItStaysEnRouteUntilDone) {
  auto node = open();
  manager::Outbox out;
  node->onRequests({wireTask(kThreeStops, "q1")}, 1'000'000, out);
  node->onRobotState(robotAt("r1", 0, 1'000'000), 1'000'000);
  out = {};
  node->tick(2'000'000, out);
  ASSERT_EQ(out.assignments.size(), 1u);
  const auto rev = out.assignments[0].revision;
  auto report = [&](msg::TaskState st, std::uint32_t step, std::int64_t now) {
    out = {};
    node->onStatus({"r1", "m-1", rev, st, 0.0f, "", now, step}, now, out);
    return out.events;
  };
  auto ev = report(msg::TaskState::EnRoute, 1, 3'000'000);
  ASSERT_EQ(ev.size(), 1u);
  EXPECT_EQ(ev[0].state, msg::TaskState::EnRoute);
  EXPECT_EQ(ev[0].step, 1u);
  const auto seq = ev[0].seq;
  EXPECT_TRUE(report(msg::TaskState::Loading, 1, 4'000'000).empty()) << "the same stop: nothing new";
  ev = report(msg::TaskState::Delivering, 2, 5'000'000);
  ASSERT_EQ(ev.size(), 1u);
  EXPECT_EQ(ev[0].state, msg::TaskState::EnRoute) << "a multi-stop task has no loading phase of its own";
  EXPECT_EQ(ev[0].step, 2u);
  EXPECT_EQ(ev[0].seq, seq) << "a stop is no transition: the seq stays";
  EXPECT_EQ(ev[0].reason, "step 2 of 3: drop L-1 at D-1");
  EXPECT_TRUE(report(msg::TaskState::Unloading, 2, 6'000'000).empty());
  ev = report(msg::TaskState::Delivering, 3, 7'000'000);
  ASSERT_EQ(ev.size(), 1u);
  EXPECT_EQ(ev[0].step, 3u);
  EXPECT_EQ(ev[0].reason, "step 3 of 3: wait");
  ev = report(msg::TaskState::Done, 3, 8'000'000);
  ASSERT_EQ(ev.size(), 1u);
  EXPECT_EQ(ev[0].state, msg::TaskState::Done);
  EXPECT_EQ(ev[0].step, 3u);
  EXPECT_GT(ev[0].seq, seq);
  EXPECT_EQ(node->dispatcher().counters().done, 1);
}

TEST_F(Multistop, EveryStopCountsAsAStationVisitForCapacity) {
  settings_.stationCapacity = 1;
  auto node = open();
  manager::Outbox out;
  // The multi-stop task's second stop is X; a go-to X must wait while it is active.
  node->onRequests({wireTask(R"({"id": "m-1", "steps": [{"action": "goto", "station": "P-1"},
                                                         {"action": "goto", "station": "X"}]})",
                             "q1")},
                   1'000'000, out);
  node->onRobotState(robotAt("r1", 0, 1'000'000), 1'000'000);
  out = {};
  node->tick(2'000'000, out);
  ASSERT_EQ(out.assignments.size(), 1u);
  node->onRequests({wireTask(R"({"id": "g-1", "kind": "goto", "station": "X"})", "q2")}, 3'000'000, out);
  node->onRobotState(robotAt("r2", 9, 3'000'000), 3'000'000);
  out = {};
  node->tick(4'000'000, out);
  EXPECT_TRUE(out.assignments.empty()) << "X is taken by the multi-stop task's second stop";
}

TEST(MultistopTravel, CostIsTheDriveToTheFirstStopAndOnThroughTheOthers) {
  Task t;
  t.id = "m";
  t.kind = TaskKind::Multistop;
  t.steps = {{StepAction::Goto, "D-1", "", 0}, {StepAction::Wait, "", "", 5}, {StepAction::Goto, "X", "", 0}};
  RobotInfo r;
  r.pose = {0, 1, 0};
  const double s = manager::makeTravelModel(multistopStations(), nullptr, 2.0)(t)(r);
  EXPECT_NEAR(s, (5.0 + 4.0) / 2.0, 1e-9);
}
