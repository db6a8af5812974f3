// Multi-stop tasks: the steps' wire form, and every way a step can be wrong, each named by its path.

#include <gtest/gtest.h>

#include <algorithm>

#include "fleet/fleet/station_map.hpp"
#include "fleet/fleet/task.hpp"

namespace fleet {
namespace {

StationMap stepStations() {
  auto m = StationMap::fromJson(nlohmann::json::parse(R"({"stations": [
    {"name": "P-1", "x": 0, "y": 0, "kinds": ["pickup"]},
    {"name": "D-2", "x": 10, "y": 0, "kinds": ["dropoff"]},
    {"name": "X", "x": 5, "y": 5, "kinds": ["parking"]},
    {"name": "C-1", "x": 0, "y": 10, "kinds": ["charging"]}]})"));
  EXPECT_TRUE(m) << m.error().message;
  return std::move(m).value();
}

constexpr const char* kFiveSteps = R"({"id": "m-1", "kind": "multistop", "steps": [
    {"action": "pick", "station": "P-1", "load_id": "L-42", "duration_ns": 2000000000},
    {"action": "drop", "station": "D-2", "load_id": "L-42"},
    {"action": "wait", "duration_ns": 5000000000},
    {"action": "goto", "station": "X"},
    {"action": "charge", "station": "C-1"}]})";

/// The one reason given for `path`, or "" when none is (failing the test if there are others).
std::string reasonAt(const std::string& text, const std::string& path) {
  const auto st = stepStations();
  auto r = parseTask(nlohmann::json::parse(text), &st);
  EXPECT_FALSE(r) << text;
  if (r) {
    return "";
  }
  std::string found;
  for (const auto& f : r.error().fields) {
    EXPECT_EQ(f.path, path) << f.reason;
    if (f.path == path) {
      found = f.reason;
    }
  }
  return found;
}

std::string withSteps(const std::string& steps) {
  return R"({"id": "m-1", "kind": "multistop", "steps": )" + steps + "}";
}

TEST(TaskSteps, ParsesFiveStepsAndRoundTrips) {
  const auto st = stepStations();
  auto r = parseTask(nlohmann::json::parse(kFiveSteps), &st);
  ASSERT_TRUE(r) << r.error().message;
  EXPECT_EQ(r->kind, TaskKind::Multistop);
  ASSERT_EQ(r->steps.size(), 5u);
  EXPECT_EQ(r->steps[0], (TaskStep{StepAction::Pick, "P-1", "L-42", 2'000'000'000}));
  EXPECT_EQ(r->steps[2], (TaskStep{StepAction::Wait, "", "", 5'000'000'000}));
  EXPECT_EQ(r->steps[4].action, StepAction::Charge);
  auto again = parseTask(toJson(*r), &st);
  ASSERT_TRUE(again) << again.error().message;
  EXPECT_EQ(*again, *r);
  // The stops in order, a wait without a station being none.
  std::vector<std::string> stops;
  for (const auto* s : taskStops(*r)) {
    stops.push_back(*s);
  }
  EXPECT_EQ(stops, (std::vector<std::string>{"P-1", "D-2", "X", "C-1"}));
  EXPECT_EQ(taskDwellNs(*r), 7'000'000'000);
}

TEST(TaskSteps, KindMayBeLeftOutWithSteps) {
  const auto st = stepStations();
  auto r =
      parseTask(nlohmann::json::parse(R"({"id": "m", "steps": [{"action": "goto", "station": "X"}]})"), &st);
  ASSERT_TRUE(r) << r.error().message;
  EXPECT_EQ(r->kind, TaskKind::Multistop);
  EXPECT_EQ(toJson(*r)["kind"], "multistop");
  // Without steps the kind is still required.
  EXPECT_FALSE(parseTask(nlohmann::json::parse(R"({"id": "m", "station": "X"})"), &st));
}

TEST(TaskSteps, UnknownStationIsNamedByItsPath) {
  EXPECT_EQ(
      reasonAt(withSteps(R"([{"action": "goto", "station": "X"}, {"action": "goto", "station": "NOPE"}])"),
               "steps[1].station"),
      "unknown station 'NOPE'");
}

TEST(TaskSteps, StationOfTheWrongKindForTheAction) {
  EXPECT_EQ(reasonAt(withSteps(R"([{"action": "pick", "station": "D-2", "load_id": "L"},
                                  {"action": "drop", "station": "D-2", "load_id": "L"}])"),
                     "steps[0].station"),
            "station 'D-2' is not a pickup station");
  EXPECT_EQ(reasonAt(withSteps(R"([{"action": "charge", "station": "X"}])"), "steps[0].station"),
            "station 'X' is not a charging station");
}

TEST(TaskSteps, PickAndDropNeedALoadId) {
  EXPECT_EQ(reasonAt(withSteps(R"([{"action": "pick", "station": "P-1"}])"), "steps[0].load_id"),
            "required for a pick step");
  EXPECT_EQ(
      reasonAt(withSteps(R"([{"action": "goto", "station": "X", "load_id": "L"}])"), "steps[0].load_id"),
      "not allowed for a goto step");
}

TEST(TaskSteps, DropOfALoadNotPicked) {
  EXPECT_EQ(reasonAt(withSteps(R"([{"action": "pick", "station": "P-1", "load_id": "A"},
                                  {"action": "drop", "station": "D-2", "load_id": "A"},
                                  {"action": "drop", "station": "D-2", "load_id": "A"}])"),
                     "steps[2].load_id"),
            "load 'A' is not on the robot here (no pick of it before)");
}

TEST(TaskSteps, ALoadPickedTwiceOrNeverDropped) {
  EXPECT_EQ(reasonAt(withSteps(R"([{"action": "pick", "station": "P-1", "load_id": "A"},
                                  {"action": "pick", "station": "P-1", "load_id": "A"},
                                  {"action": "drop", "station": "D-2", "load_id": "A"}])"),
                     "steps[1].load_id"),
            "load 'A' is already on the robot (picked at steps[0])");
  EXPECT_EQ(
      reasonAt(withSteps(R"([{"action": "pick", "station": "P-1", "load_id": "B"}])"), "steps[0].load_id"),
      "load 'B' is picked but never dropped");
}

TEST(TaskSteps, TooManySteps) {
  std::string steps = "[";
  for (int i = 0; i < 17; ++i) {
    steps += std::string(i > 0 ? "," : "") + R"({"action": "goto", "station": "X"})";
  }
  EXPECT_EQ(reasonAt(withSteps(steps + "]"), "steps"), "at most 16 steps, got 17");
  EXPECT_EQ(reasonAt(withSteps("[]"), "steps"), "required for a multistop task (1 to 16 steps)");
}

TEST(TaskSteps, WaitNeedsADurationAndAStopToWaitAt) {
  EXPECT_EQ(reasonAt(withSteps(R"([{"action": "goto", "station": "X"}, {"action": "wait"}])"),
                     "steps[1].duration_ns"),
            "required (> 0) for a wait step");
  EXPECT_EQ(reasonAt(withSteps(R"([{"action": "wait", "duration_ns": 5}])"), "steps[0].station"),
            "required for a wait that is the first step (there is no stop before it to wait at)");
}

TEST(TaskSteps, ActionsAndTypes) {
  EXPECT_EQ(reasonAt(withSteps(R"([{"action": "dance", "station": "X"}])"), "steps[0].action"),
            "unknown action 'dance' (expected goto, pick, drop, wait or charge)");
  EXPECT_EQ(reasonAt(withSteps(R"([{"station": "X"}])"), "steps[0].action"),
            "required (goto, pick, drop, wait or charge)");
  EXPECT_EQ(reasonAt(withSteps(R"([{"action": "goto", "station": "X", "speed": 2}])"), "steps[0].speed"),
            "unknown field");
  EXPECT_EQ(reasonAt(withSteps(R"([{"action": "wait", "station": "X", "duration_ns": -1}])"),
                     "steps[0].duration_ns"),
            "must be an integer in [0, 3600e9] ns");
  EXPECT_EQ(reasonAt(withSteps(R"("goto X")"), "steps"), "expected an array of steps, got a string");
  EXPECT_EQ(reasonAt(withSteps(R"([7])"), "steps[0]"), "expected a step object, got an integer");
}

TEST(TaskSteps, StepsBelongToMultistopTasksOnly) {
  EXPECT_EQ(
      reasonAt(
          R"({"id": "t", "kind": "goto", "station": "X", "steps": [{"action": "goto", "station": "X"}]})",
          "steps"),
      "not allowed for a goto task");
  EXPECT_EQ(
      reasonAt(withSteps(R"([{"action": "goto", "station": "X"}])").replace(1, 0, R"("pickup": "P-1", )"),
               "pickup"),
      "not allowed for a multistop task");
}

TEST(TaskSteps, PathsInABatchNameTheTask) {
  const auto st = stepStations();
  auto r = parseTasks(
      nlohmann::json::parse(R"({"tasks": [)" + withSteps(R"([{"action": "goto", "station": "Q"}])") + "]}"),
      &st);
  ASSERT_FALSE(r);
  ASSERT_EQ(r.error().fields.size(), 1u);
  EXPECT_EQ(r.error().fields[0].path, "tasks[0].steps[0].station");
}

}  // namespace
}  // namespace fleet
