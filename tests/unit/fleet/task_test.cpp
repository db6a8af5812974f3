#include "fleet/fleet/task.hpp"

#include <gtest/gtest.h>

#include "fleet/fleet/station_map.hpp"

namespace fleet {
namespace {

StationMap testStations() {
  auto m = StationMap::fromJson(nlohmann::json::parse(R"({"stations": [
    {"name": "P-1", "x": 0, "y": 0, "kinds": ["pickup"]},
    {"name": "D-1", "x": 10, "y": 0, "theta": 1.5, "kinds": ["dropoff"]},
    {"name": "DOCK", "x": 5, "y": 5, "kinds": ["pickup", "dropoff"]},
    {"name": "C-1", "x": 0, "y": 10, "kinds": ["charging"]},
    {"name": "K-1", "x": 10, "y": 10, "kinds": ["parking"]}]})"));
  EXPECT_TRUE(m) << m.error().message;
  return std::move(m).value();
}

std::vector<FieldError> errorsOf(const std::string& text, const StationMap* st) {
  auto r = parseTask(nlohmann::json::parse(text), st);
  EXPECT_FALSE(r) << text;
  return r ? std::vector<FieldError>{} : r.error().fields;
}

TEST(StationMap, ParsesAndFindsByKind) {
  auto m = testStations();
  EXPECT_EQ(m.size(), 5u);
  ASSERT_NE(m.find("D-1"), nullptr);
  EXPECT_DOUBLE_EQ(m.find("D-1")->pose.x, 10.0);
  EXPECT_DOUBLE_EQ(m.find("D-1")->pose.theta, 1.5);
  EXPECT_TRUE(m.find("DOCK")->has(StationKind::Pickup));
  EXPECT_TRUE(m.find("DOCK")->has(StationKind::Dropoff));
  EXPECT_FALSE(m.find("DOCK")->has(StationKind::Charging));
  EXPECT_EQ(m.ofKind(StationKind::Pickup).size(), 2u);
  EXPECT_EQ(m.find("nope"), nullptr);
}

TEST(StationMap, ReportsEveryProblem) {
  auto m = StationMap::fromJson(nlohmann::json::parse(R"([
    {"name": "A", "x": 0, "y": 0, "kinds": ["dock"]},
    {"name": "B", "y": 0, "kinds": ["pickup"]},
    {"name": "A", "x": 0, "y": 0, "kinds": ["pickup"]},
    {"name": "A", "x": 1, "y": 1, "kinds": ["dropoff"]}])"));
  ASSERT_FALSE(m);
  EXPECT_NE(m.error().message.find("[0].kinds[0]: unknown kind \"dock\""), std::string::npos)
      << m.error().message;
  EXPECT_NE(m.error().message.find("[1].x: required"), std::string::npos);
  EXPECT_NE(m.error().message.find("[3]: station 'A' defined twice"), std::string::npos);
}

TEST(Task, ParsesTransportWithAllFields) {
  auto st = testStations();
  auto r = parseTask(nlohmann::json::parse(R"({"id": "t-1", "kind": "transport", "pickup": "P-1",
      "dropoff": "D-1", "load_duration_ns": 2000000000, "unload_duration_ns": 3000000000,
      "priority": 5, "deadline_ns": 9000000000, "created_ns": 1000})"),
                     &st);
  ASSERT_TRUE(r) << r.error().message;
  EXPECT_EQ(r->id, "t-1");
  EXPECT_EQ(r->kind, TaskKind::Transport);
  EXPECT_EQ(r->pickup, "P-1");
  EXPECT_EQ(r->dropoff, "D-1");
  EXPECT_EQ(r->loadNs, 2'000'000'000);
  EXPECT_EQ(r->unloadNs, 3'000'000'000);
  EXPECT_EQ(r->priority, 5);
  EXPECT_EQ(r->deadlineNs, 9'000'000'000);
  EXPECT_EQ(r->createdNs, 1000);
}

TEST(Task, JsonRoundTripIsIdentity) {
  auto st = testStations();
  std::vector<Task> tasks = {
      {"a", TaskKind::Transport, "P-1", "DOCK", "", "", 5, 6, -3, 100, 50},
      {"b", TaskKind::Goto, "", "", "K-1", "r1", 0, 0, 1000, 0, 0},
      {"c", TaskKind::Charge, "", "", "", "r2", 0, 0, 0, 0, 7},
      {"d", TaskKind::Park, "", "", "K-1", "", 0, 0, kMinPriority, 0, 0},
  };
  for (const auto& t : tasks) {
    auto back = parseTask(toJson(t), &st);
    ASSERT_TRUE(back) << t.id << ": " << back.error().message;
    EXPECT_EQ(*back, t);
  }
}

TEST(Task, CanonicalBodyDecidesIdempotency) {
  const auto a = parseTask(nlohmann::json::parse(
      R"({"kind":"transport","id":"x","dropoff":"D-1","pickup":"P-1","priority":0,"created_ns":5})"));
  const auto b = parseTask(nlohmann::json::parse(
      R"({"id":"x","pickup":"P-1","kind":"transport","dropoff":"D-1","created_ns":99})"));
  const auto c =
      parseTask(nlohmann::json::parse(R"({"id":"x","kind":"transport","pickup":"P-1","dropoff":"D-1",
      "priority":1})"));
  ASSERT_TRUE(a && b && c);
  // Key order, explicit defaults and created_ns do not matter; any real field does.
  EXPECT_EQ(canonicalBody(*a), canonicalBody(*b));
  EXPECT_NE(canonicalBody(*a), canonicalBody(*c));
  EXPECT_EQ(canonicalBody(*a), R"({"dropoff":"D-1","id":"x","kind":"transport","pickup":"P-1"})");
}

TEST(Task, ValidationNamesFieldAndReason) {
  auto st = testStations();
  auto e = errorsOf(R"({"id": "t 1", "kind": "transport", "pickup": "P-9", "dropoff": "C-1", "station": "K-1",
      "priority": 5000, "colour": "red"})",
                    &st);
  const std::vector<FieldError> expect = {
      {"colour", "unknown field"},
      {"priority", "must be in [-1000, 1000]"},
  };
  EXPECT_EQ(e, expect) << "type/range problems stop before semantic checks";

  e = errorsOf(R"({"id": "t 1", "kind": "transport", "pickup": "P-9", "dropoff": "C-1", "station": "K-1"})",
               &st);
  const std::vector<FieldError> expect2 = {
      {"id", "not a valid id (1-63 characters of A-Z a-z 0-9 _ . : -)"},
      {"pickup", "unknown station 'P-9'"},
      {"dropoff", "station 'C-1' is not a dropoff station"},
      {"station", "not allowed for a transport task"},
  };
  EXPECT_EQ(e, expect2);
}

TEST(Task, ValidationOfTypesAndKinds) {
  auto st = testStations();
  EXPECT_EQ(errorsOf(R"({"kind": "transport"})", &st), (std::vector<FieldError>{{"id", "required"}}));
  EXPECT_EQ(errorsOf(R"({"id": 7, "kind": "fly"})", &st),
            (std::vector<FieldError>{
                {"id", "expected a string, got an integer"},
                {"kind", "unknown kind 'fly' (expected transport, goto, charge, park or multistop)"}}));
  EXPECT_EQ(errorsOf(R"({"id": "a", "kind": "transport", "pickup": "P-1"})", &st),
            (std::vector<FieldError>{{"dropoff", "required for a transport task"}}));
  EXPECT_EQ(errorsOf(R"({"id": "a", "kind": "goto"})", &st),
            (std::vector<FieldError>{{"station", "required for a goto task"}}));
  EXPECT_EQ(errorsOf(R"({"id": "a", "kind": "charge", "station": "K-1", "load_duration_ns": 5})", &st),
            (std::vector<FieldError>{{"load_duration_ns", "not allowed for a charge task"},
                                     {"station", "station 'K-1' is not a charging station"}}));
  EXPECT_EQ(
      errorsOf(R"({"id": "a", "kind": "transport", "pickup": "P-1", "dropoff": "D-1", "deadline_ns": 1.5})",
               &st),
      (std::vector<FieldError>{{"deadline_ns", "expected an integer, got a number"}}));
  EXPECT_EQ(errorsOf(R"({"id": "a", "kind": "transport", "pickup": "DOCK", "dropoff": "DOCK"})", &st),
            (std::vector<FieldError>{{"dropoff", "must differ from pickup"}}));
  EXPECT_EQ(
      errorsOf(R"({"id": "a", "kind": "transport", "pickup": "P-1", "dropoff": "D-1", "deadline_ns": -1})",
               &st),
      (std::vector<FieldError>{{"deadline_ns", "must be in [0, 9223372036854775807]"}}));
  EXPECT_EQ(errorsOf(R"([1])", &st), (std::vector<FieldError>{{"", "expected a task object, got an array"}}));
  // Without a station map only the syntax of station names is checked.
  EXPECT_TRUE(parseTask(nlohmann::json::parse(R"({"id": "a", "kind": "goto", "station": "anywhere"})")));
}

TEST(Task, BatchPathsNameTheElement) {
  auto st = testStations();
  auto r = parseTasks(nlohmann::json::parse(R"({"tasks": [
      {"id": "a", "kind": "goto", "station": "K-1"},
      {"id": "b", "kind": "goto", "station": "Z"},
      {"id": "a", "kind": "park"}]})"),
                      &st);
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error().fields, (std::vector<FieldError>{{"tasks[1].station", "unknown station 'Z'"},
                                                       {"tasks[2].id", "duplicate id 'a' in this batch"}}));
  EXPECT_EQ(r.error().message,
            "tasks[1].station: unknown station 'Z'; tasks[2].id: duplicate id 'a' in this batch");
  auto arr = parseTasks(
      nlohmann::json::parse(R"([{"id": "a", "kind": "park"}, {"id": "b", "kind": "charge"}])"), &st);
  ASSERT_TRUE(arr);
  EXPECT_EQ(arr->size(), 2u);
  auto one = parseTasks(nlohmann::json::parse(R"({"id": "a", "kind": "park"})"), &st);
  ASSERT_TRUE(one);
  EXPECT_EQ(one->size(), 1u);
  auto bad = parseTasks(nlohmann::json::parse(R"([{"id": "a", "kind": "park", "pickup": "P-1"}])"), &st);
  ASSERT_FALSE(bad);
  EXPECT_EQ(bad.error().fields.at(0).path, "[0].pickup");
}

TEST(Task, AChargeOrParkTaskWithoutAStationNeedsOneOfItsKindOnTheSite) {
  auto st = testStations();
  EXPECT_TRUE(parseTask(nlohmann::json::parse(R"({"id": "a", "kind": "park"})"), &st));
  EXPECT_TRUE(parseTask(nlohmann::json::parse(R"({"id": "a", "kind": "charge"})"), &st));
  StationMap noParking;
  ASSERT_TRUE(noParking.add({"P-1", {1, 1, 0}, static_cast<std::uint8_t>(StationKind::Pickup)}));
  EXPECT_EQ(errorsOf(R"({"id": "a", "kind": "park"})", &noParking),
            (std::vector<FieldError>{{"station", "no parking station on this site to choose from"}}));
  auto batch = parseTasks(nlohmann::json::parse(R"([{"id": "a", "kind": "charge"}])"), &noParking);
  ASSERT_FALSE(batch);
  EXPECT_EQ(batch.error().fields,
            (std::vector<FieldError>{{"[0].station", "no charging station on this site to choose from"}}));
  // Naming a station still works the same; without a site only the syntax is checked.
  EXPECT_EQ(errorsOf(R"({"id": "a", "kind": "park", "station": "P-1"})", &noParking),
            (std::vector<FieldError>{{"station", "station 'P-1' is not a parking station"}}));
  EXPECT_TRUE(parseTask(nlohmann::json::parse(R"({"id": "a", "kind": "park"})")));
}

TEST(StationMapTest, AcceptsTheSimulatorScenarioForm) {
  auto m = StationMap::fromJson(nlohmann::json::parse(R"({"name": "x", "map": {}, "stations": [
    {"name": "PARK-1", "kind": "parking", "pose": [4.0, 1.25, 1.5708]},
    {"name": "P-1", "kinds": ["pickup", "dropoff"], "x": 1, "y": 2}]})"));
  ASSERT_TRUE(m) << m.error().message;
  const Station* park = m->find("PARK-1");
  ASSERT_NE(park, nullptr);
  EXPECT_DOUBLE_EQ(park->pose.x, 4.0);
  EXPECT_DOUBLE_EQ(park->pose.theta, 1.5708);
  EXPECT_TRUE(park->has(StationKind::Parking));
  auto bad = StationMap::fromJson(
      nlohmann::json::parse(R"({"stations": [{"name": "Q", "kind": "dock", "pose": [1]}]})"));
  ASSERT_FALSE(bad);
  EXPECT_NE(bad.error().message.find("unknown kind"), std::string::npos);
  EXPECT_NE(bad.error().message.find("stations[0].y"), std::string::npos);
}

}  // namespace
}  // namespace fleet
