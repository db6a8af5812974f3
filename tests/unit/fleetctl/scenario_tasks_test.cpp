#include "scenario_tasks.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <set>

#include "fleet/core/config.hpp"
#include "fleet/scenario/scenario.hpp"

namespace fleet::ctl {
namespace {

using nlohmann::json;

json stations() {
  return json::parse(R"({"stations": [
    {"name": "P-1", "kind": "pickup", "pose": [1, 1, 0]}, {"name": "P-2", "kind": "pickup", "pose": [2, 1, 0]},
    {"name": "D-1", "kind": "dropoff", "pose": [1, 5, 0]}, {"name": "D-2", "kind": "dropoff", "pose": [2, 5, 0]},
    {"name": "PARK-1", "kind": "parking", "pose": [3, 3, 0]}]})");
}

json withTasks(const json& tasks) {
  json s = stations();
  s["tasks"] = tasks;
  return s;
}

/// Every problem parseScenarioTasks reports (empty if none).
std::vector<std::string> problems(const json& scenario) {
  try {
    parseScenarioTasks(scenario, "small_warehouse.json");
  } catch (const ConfigError& e) {
    return e.problems();
  }
  return {};
}

bool has(const std::vector<std::string>& ps, const std::string& text) {
  for (const auto& p : ps) {
    if (p.find(text) != std::string::npos) {
      return true;
    }
  }
  return false;
}

std::string all(const std::vector<std::string>& ps) {
  std::string s;
  for (const auto& p : ps) {
    s += p + "\n";
  }
  return s;
}

TEST(ScenarioTasks, NoListIsNotAnError) {
  EXPECT_FALSE(parseScenarioTasks(stations(), "s.json").has_value());
}

TEST(ScenarioTasks, GoodListKeepsOrderIdsAndPriorities) {
  auto list = parseScenarioTasks(withTasks(json::parse(R"([
    {"at_s": 0, "pickup": "P-1", "dropoff": "D-2"},
    {"at_s": 4.5, "pickup": "P-2", "dropoff": "D-1", "id": "order-17", "priority": -1000},
    {"at_s": 2, "pickup": "P-1", "dropoff": "D-1", "id": "task-001", "priority": 1000},
    {"at_s": 3, "pickup": "P-2", "dropoff": "D-2"}])")),
                                 "s.json");
  ASSERT_TRUE(list.has_value());
  ASSERT_EQ(list->size(), 4u);
  // Generated ids follow the place in the list and never take an id given explicitly.
  EXPECT_EQ((*list)[0].id, "task-001-2");
  EXPECT_EQ((*list)[1].id, "order-17");
  EXPECT_EQ((*list)[2].id, "task-001");
  EXPECT_EQ((*list)[3].id, "task-004");
  EXPECT_DOUBLE_EQ((*list)[1].atS, 4.5);
  EXPECT_EQ((*list)[1].pickup, "P-2");
  EXPECT_EQ((*list)[1].dropoff, "D-1");
  EXPECT_EQ((*list)[1].priority, -1000);
  EXPECT_FALSE((*list)[0].priority.has_value());

  const json r = toTaskRequest((*list)[1]);
  EXPECT_EQ(r["id"], "order-17");
  EXPECT_EQ(r["kind"], "transport");
  EXPECT_EQ(r["pickup"], "P-2");
  EXPECT_EQ(r["dropoff"], "D-1");
  EXPECT_EQ(r["priority"], -1000);
  EXPECT_FALSE(toTaskRequest((*list)[0]).contains("priority"));
}

TEST(ScenarioTasks, EveryBadEntryIsNamedWithItsKeyPathAllAtOnce) {
  const auto ps = problems(withTasks(json::parse(R"([
    {"at_s": 0, "pickup": "P-1", "dropoff": "D-1", "id": "a"},
    {"at_s": -1, "pickup": "P-9", "dropoff": "D-1"},
    {"at_s": "soon", "pickup": "D-2", "dropoff": "P-1"},
    {"pickup": 3, "dropoff": "PARK-1", "id": "a"},
    {"at_s": 1, "pickup": "P-1", "dropoff": "D-1", "priority": 1001, "prio": 1},
    {"at_s": 1, "pickup": "P-1", "dropoff": "D-1", "priority": 1.5, "id": "bad id!"},
    {"at_s": 1, "dropoff": "D-1", "id": 7},
    "P-1 to D-1"])")));
  const std::string text = all(ps);
  EXPECT_TRUE(has(ps, "small_warehouse.json: tasks[1].at_s: expected a number >= 0, got -1")) << text;
  EXPECT_TRUE(has(ps, "small_warehouse.json: tasks[1].pickup: unknown station 'P-9'")) << text;
  EXPECT_TRUE(has(ps, "small_warehouse.json: tasks[2].at_s: expected a number >= 0, got a string")) << text;
  EXPECT_TRUE(has(ps, "tasks[2].pickup: station 'D-2' is a dropoff station; expected a pickup station"))
      << text;
  EXPECT_TRUE(has(ps, "tasks[2].dropoff: station 'P-1' is a pickup station; expected a dropoff station"))
      << text;
  EXPECT_TRUE(has(ps, "tasks[3].at_s: missing")) << text;
  EXPECT_TRUE(has(ps, "tasks[3].pickup: expected a string, got an integer")) << text;
  EXPECT_TRUE(has(ps, "tasks[3].dropoff: station 'PARK-1' is a parking station")) << text;
  EXPECT_TRUE(has(ps, "tasks[3].id: duplicate id 'a' (also tasks[0])")) << text;
  EXPECT_TRUE(has(ps, "tasks[4].priority: expected an integer in [-1000, 1000], got 1001")) << text;
  EXPECT_TRUE(has(ps, "tasks[4].prio: unknown key")) << text;
  EXPECT_TRUE(has(ps, "tasks[5].priority: expected an integer in [-1000, 1000], got a number")) << text;
  EXPECT_TRUE(has(ps, "tasks[5].id: expected 1 to 63 characters")) << text;
  EXPECT_TRUE(has(ps, "tasks[6].pickup: missing")) << text;
  EXPECT_TRUE(has(ps, "tasks[6].id: expected a string, got an integer")) << text;
  EXPECT_TRUE(has(ps, "tasks[7]: expected an object, got a string")) << text;
  EXPECT_EQ(ps.size(), 16u) << text;  // nothing about the good entry tasks[0]
  EXPECT_FALSE(has(ps, "small_warehouse.json: tasks[0]")) << text;
}

// A multi-stop entry carries its steps as the HTTP API takes them, checked by the fleet manager's
// rules at start: what the manager would refuse is named with the entry's key path.
TEST(ScenarioTasks, AMultiStopEntryIsPostedWithItsStepsAndItsBadStepsAreNamed) {
  const json steps = json::parse(R"([{"action": "pick", "station": "P-1", "load_id": "L-1"},
    {"action": "drop", "station": "D-2", "load_id": "L-1"}, {"action": "wait", "duration_ns": 3000000000}])");
  const auto list =
      parseScenarioTasks(withTasks(json::array({{{"at_s", 1}, {"steps", steps}, {"id", "m-1"}}})), "s.json");
  ASSERT_TRUE(list.has_value());
  ASSERT_EQ(list->size(), 1U);
  EXPECT_TRUE((*list)[0].pickup.empty());
  const json r = toTaskRequest((*list)[0]);
  EXPECT_EQ(r["kind"], "multistop");
  EXPECT_EQ(r["steps"], steps);
  EXPECT_FALSE(r.contains("pickup"));

  const auto ps = problems(withTasks(json::parse(R"([
    {"at_s": 0, "steps": [{"action": "pick", "station": "P-9", "load_id": "L-1"},
                          {"action": "drop", "station": "P-1", "load_id": "L-1"}]},
    {"at_s": 0, "pickup": "P-1", "steps": [{"action": "goto", "station": "D-1"}]},
    {"at_s": 0, "steps": [{"action": "fly", "station": "D-1"}]},
    {"at_s": 0, "steps": "P-1 then D-1"},
    {"at_s": 0, "steps": [{"action": "goto", "station": "D-1"}, {"action": "wait"}]}])")));
  const std::string text = all(ps);
  EXPECT_TRUE(has(ps, "small_warehouse.json: tasks[0].steps[0].station: unknown station 'P-9'")) << text;
  EXPECT_TRUE(has(ps, "tasks[0].steps[1].station")) << text;  // a drop at a pickup station
  EXPECT_TRUE(has(ps, "tasks[1].steps: a task has steps or a pickup and a drop-off, not both")) << text;
  EXPECT_TRUE(has(ps, "tasks[2].steps[0].action")) << text;
  EXPECT_TRUE(has(ps, "tasks[3].steps: expected an array of steps")) << text;
  EXPECT_TRUE(has(ps, "tasks[4].steps[1]")) << text;  // a wait without a duration
}

TEST(ScenarioTasks, TasksMustBeAnArray) {
  const auto ps = problems(withTasks(json{{"at_s", 0}}));
  ASSERT_EQ(ps.size(), 1u) << all(ps);
  EXPECT_EQ(ps[0], "small_warehouse.json: tasks: expected an array, got an object");
}

// The demo scenario's list: the default demo load (20 robots x 0.75 per minute over 180 s = 45
// tasks) spread over the 180 s and over every pickup and drop-off station; the simulator accepts
// (and ignores) the key.
TEST(ScenarioTasks, SmallWarehouseListIsTheDemoLoad) {
  const std::string path = std::string(FLEET_SOURCE_DIR) + "/sim/scenarios/small_warehouse.json";
  std::ifstream in(path);
  const json doc = json::parse(in);
  std::optional<std::vector<ScenarioTask>> list;
  ASSERT_NO_THROW(list = parseScenarioTasks(doc, path));
  ASSERT_TRUE(list.has_value());
  EXPECT_EQ(list->size(), 45u);
  std::set<std::string> ids, pickups, dropoffs;
  double last = 0;
  for (const auto& t : *list) {
    ids.insert(t.id);
    pickups.insert(t.pickup);
    dropoffs.insert(t.dropoff);
    EXPECT_GE(t.atS, last);
    last = t.atS;
    EXPECT_LT(t.atS, 180.0);
  }
  EXPECT_EQ(ids.size(), list->size());
  EXPECT_GT(last, 170.0);
  EXPECT_EQ(pickups, (std::set<std::string>{"P-1", "P-2", "P-3", "P-4", "P-5"}));
  EXPECT_EQ(dropoffs, (std::set<std::string>{"D-1", "D-2", "D-3", "D-4"}));
  EXPECT_NO_THROW(sim::loadScenario(path));
}

// fleetctl's copy of a scenario that names its site: the path made absolute (the run's copy lives
// elsewhere), the site's stations at hand, and a template's robot description taken into it.
TEST(ScenarioSite, ARunsCopyFindsTheSiteAndItsStations) {
  const std::string path = std::string(FLEET_SOURCE_DIR) + "/sim/scenarios/small_warehouse.json";
  const json raw = json::parse(std::ifstream(path));
  ASSERT_EQ(raw["site"], "small_warehouse.site.json");
  const json s = resolveScenarioSite(raw, path);
  EXPECT_EQ(s["site"], std::string(FLEET_SOURCE_DIR) + "/sim/scenarios/small_warehouse.site.json");
  EXPECT_EQ(scenarioStations(s).size(), 32u);
  EXPECT_EQ(scenarioStations(raw).size(), 0u);  // not resolved: no stations of its own
  const json t = inlineSiteRobot(raw, path);
  EXPECT_FALSE(t.contains("site"));
  EXPECT_DOUBLE_EQ(t["robot_defaults"]["radius"].get<double>(), 0.3);
  EXPECT_EQ(t["robot_defaults"]["sensors"]["rays"], 72);
  EXPECT_DOUBLE_EQ(t["robot_defaults"]["sensors"]["range_sigma"].get<double>(), 0.01);  // the scenario's own
  try {
    (void)resolveScenarioSite(json{{"site", "nowhere.site.json"}}, path);
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("cannot read the site file"), std::string::npos);
  }
}

TEST(ScenarioSite, AnInlineScenarioSplitsIntoASiteAndTheRest) {
  json inlineScenario = stations();
  inlineScenario["map"] = {{"rows", {"....", "...."}}, {"resolution", 1.0}};
  inlineScenario["robot_defaults"] = {{"radius", 0.2}, {"battery", {{"initial", 0.5}}}};
  inlineScenario["robots"] = json::array();
  const auto [site, rest] = splitSite(inlineScenario);
  EXPECT_EQ(site["format"], "fleet-site/1");
  EXPECT_EQ(site["stations"].size(), 5u);
  EXPECT_DOUBLE_EQ(site["robot"]["radius"].get<double>(), 0.2);
  EXPECT_FALSE(rest.contains("map"));
  EXPECT_FALSE(rest.contains("stations"));
  EXPECT_FALSE(rest["robot_defaults"].contains("radius"));
  EXPECT_TRUE(rest["robot_defaults"].contains("battery"));
}

}  // namespace
}  // namespace fleet::ctl
