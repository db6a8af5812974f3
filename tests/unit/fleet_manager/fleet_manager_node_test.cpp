#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <set>

#include <filesystem>
#include <fstream>

#include "fleet/fleet/site_stations.hpp"
#include "fleet/planning/map_io.hpp"
#include "fleet/site/site_loader.hpp"
#include "fleet_manager_node.hpp"

using namespace fleet;
using ::testing::HasSubstr;

namespace {
StationMap stations() {
  auto m = StationMap::fromJson(nlohmann::json::parse(R"({"stations": [
    {"name": "P-1", "x": 1, "y": 1, "theta": 0, "kinds": ["pickup"]},
    {"name": "D-1", "x": 5, "y": 1, "theta": 0, "kinds": ["dropoff"]},
    {"name": "C-1", "x": 0, "y": 0, "theta": 0, "kinds": ["charging", "parking"]}]})"));
  EXPECT_TRUE(m);
  return *m;
}

int gRequest = 0;

// The request the WMS adapter would send for this JSON task (typed fields, parsed without the
// stations: those are the manager's to check). An empty body: a bare cancel.
msg::Task request(const std::string& id, const std::string& body, bool cancel = false) {
  msg::Task t;
  t.task_id = id;
  t.request_id = "req-" + std::to_string(++gRequest);
  t.cancel = cancel;
  if (!body.empty()) {
    const auto parsed = parseTask(nlohmann::json::parse(body));
    EXPECT_TRUE(parsed) << body;
    const Task task = parsed ? *parsed : Task{};
    t.kind = static_cast<msg::TaskKind>(static_cast<int>(task.kind));
    t.pickup = task.pickup;
    t.dropoff = task.dropoff;
    t.station = task.station;
    t.robot = task.robot;
    t.load_ns = task.loadNs;
    t.unload_ns = task.unloadNs;
    t.priority = task.priority;
  }
  return t;
}

std::string transport(const std::string& id, const std::string& pickup = "P-1") {
  return R"({"id": ")" + id + R"(", "kind": "transport", "pickup": ")" + pickup +
         R"(", "dropoff": "D-1", "load_duration_ns": 2000000000})";
}

class Node : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("fm_node_" + std::to_string(getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
    settings_.db = (dir_ / "fleet.db").string();
    settings_.stationsFile = "unused";
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::unique_ptr<manager::FleetManagerNode> open(std::int64_t now) { return open(now, stations()); }
  std::unique_ptr<manager::FleetManagerNode> open(std::int64_t now, StationMap site) {
    auto n = manager::FleetManagerNode::create(settings_, std::move(site), now);
    EXPECT_TRUE(n) << (n ? "" : n.error().message);
    return std::move(*n);
  }
  std::filesystem::path dir_;
  manager::Settings settings_;
};
}  // namespace

TEST_F(Node, RequestsAreAcknowledgedWithTheRightResult) {
  auto node = open(1'000);
  manager::Outbox out;
  auto noDropoff = request("t3", transport("t3"));
  noDropoff.dropoff.clear();
  const std::vector<msg::Task> reqs = {request("t1", transport("t1")), request("t2", transport("t2", "NOPE")),
                                       noDropoff, request("t1", transport("t1")),
                                       request("t1", R"({"id": "t1", "kind": "goto", "station": "D-1"})")};
  node->onRequests(reqs, 2'000, out);
  ASSERT_EQ(out.acks.size(), 5u);
  // Acks come in commit order (invalid ones at once, stored ones after the group commit).
  std::vector<msg::TaskAck> acks;
  for (const auto& r : reqs) {
    for (const auto& a : out.acks) {
      if (a.request_id == r.request_id) {
        acks.push_back(a);
      }
    }
  }
  ASSERT_EQ(acks.size(), 5u);
  EXPECT_EQ(acks[0].result, msg::AckResult::Stored);
  EXPECT_EQ(acks[0].state, msg::TaskState::Queued);
  EXPECT_EQ(acks[1].result, msg::AckResult::Invalid);
  EXPECT_THAT(acks[1].detail, HasSubstr("\"path\":\"pickup\""));
  EXPECT_THAT(acks[1].detail, HasSubstr("NOPE"));
  EXPECT_EQ(acks[2].result, msg::AckResult::Invalid);
  EXPECT_THAT(acks[2].detail, HasSubstr("\"path\":\"dropoff\""));
  EXPECT_EQ(acks[3].result, msg::AckResult::Duplicate);
  EXPECT_EQ(acks[4].result, msg::AckResult::Conflict);
  ASSERT_EQ(out.events.size(), 1u);
  EXPECT_EQ(out.events[0].task_id, "t1");
  EXPECT_EQ(out.events[0].state, msg::TaskState::Queued);
  EXPECT_EQ(out.events[0].seq, 1u);
}

TEST_F(Node, TheAssignmentCarriesTheTasksPriority) {
  auto node = open(0);
  manager::Outbox out;
  const std::string body =
      R"({"id": "t1", "kind": "transport", "pickup": "P-1", "dropoff": "D-1", "priority": 5})";
  node->onRequests({request("t1", body)}, 1'000'000, out);
  node->onRobotState({"r1", 1'000'000, {0, 1, 0}, {}, 0, 0, msg::RobotMode::Idle, 0.9f, "", 0.3f}, 1'000'000);
  out = {};
  node->tick(2'000'000, out);
  ASSERT_EQ(out.assignments.size(), 1u);
  EXPECT_EQ(out.assignments[0].priority, 5);
}

TEST_F(Node, TransportTaskIsAssignedWithStationGoalsAndFinishes) {
  auto node = open(0);
  manager::Outbox out;
  node->onRequests({request("t1", transport("t1"))}, 1'000'000, out);
  node->onRobotState({"r1", 1'000'000, {0, 1, 0}, {}, 0, 0, msg::RobotMode::Idle, 0.9f, "", 0.3f}, 1'000'000);
  out = {};
  node->tick(2'000'000, out);
  ASSERT_EQ(out.assignments.size(), 1u);
  const auto a = out.assignments[0];  // a copy: `out` is cleared below
  EXPECT_EQ(a.robot_id, "r1");
  EXPECT_EQ(a.task_id, "t1");
  ASSERT_EQ(a.goals.size(), 2u);
  EXPECT_EQ(a.goals[0].station, "P-1");
  EXPECT_EQ(a.goals[0].action, msg::GoalAction::Load);
  EXPECT_DOUBLE_EQ(a.goals[0].duration_s, 2.0);
  EXPECT_DOUBLE_EQ(a.goals[1].pose.x, 5.0);
  EXPECT_EQ(a.goals[1].action, msg::GoalAction::Unload);
  out = {};
  node->onStatus({"r1", "t1", a.revision, msg::TaskState::Done, 1.0f, "", 3'000'000}, 3'000'000, out);
  ASSERT_FALSE(out.events.empty());
  EXPECT_EQ(out.events.back().state, msg::TaskState::Done);
  EXPECT_EQ(node->dispatcher().counters().done, 1);
  const auto m = node->metricsJson();
  EXPECT_EQ(m["done"], 1);
  EXPECT_EQ(m["assign_latency_ms"]["samples"], 1);
}

TEST_F(Node, LostRobotsTaskIsReassignedAndStaleReportsRevoked) {
  settings_.leaseS = 1.0;
  auto node = open(0);
  manager::Outbox out;
  node->onRequests({request("t1", transport("t1"))}, 0, out);
  node->onRobotState({"r1", 0, {0, 1, 0}, {}, 0, 0, msg::RobotMode::Idle, 0.9f, "", 0.3f}, 0);
  node->tick(100'000'000, out);
  ASSERT_EQ(out.assignments.size(), 1u);
  // r1 falls silent; r2 appears.
  node->onRobotState({"r2", 1'500'000'000, {4, 1, 0}, {}, 0, 0, msg::RobotMode::Idle, 0.9f, "", 0.3f},
                     1'500'000'000);
  out = {};
  node->tick(1'600'000'000, out);
  bool requeued = false;
  for (const auto& e : out.events) {
    requeued = requeued || e.state == msg::TaskState::Requeued;
  }
  EXPECT_TRUE(requeued);
  ASSERT_FALSE(out.assignments.empty());
  EXPECT_EQ(out.assignments.back().robot_id, "r2");
  // r1 comes back and reports progress on a task it no longer holds: it is told to drop it.
  node->onRobotState({"r1", 1'700'000'000, {0, 1, 0}, {}, 0, 0, msg::RobotMode::Moving, 0.9f, "t1", 0.3f},
                     1'700'000'000);
  out = {};
  node->onStatus({"r1", "t1", 1, msg::TaskState::Loading, 0.5f, "", 1'700'000'000}, 1'700'000'000, out);
  ASSERT_EQ(out.assignments.size(), 1u);
  EXPECT_EQ(out.assignments[0].robot_id, "r1");
  EXPECT_TRUE(out.assignments[0].task_id.empty());
}

TEST_F(Node, RestartRecoversOpenTasksAndAssignments) {
  {
    auto node = open(0);
    manager::Outbox out;
    node->onRequests({request("t1", transport("t1")), request("t2", transport("t2"))}, 0, out);
    node->onRobotState({"r1", 0, {0, 1, 0}, {}, 0, 0, msg::RobotMode::Idle, 0.9f, "", 0.3f}, 0);
    node->tick(1, out);
  }
  auto node = open(10);
  EXPECT_EQ(node->dispatcher().openTasks().size(), 2u);
  ASSERT_EQ(node->recovered().assignments.size(), 1u);
  EXPECT_EQ(node->recovered().assignments[0].robot_id, "r1");
}

TEST_F(Node, CancelAnswers) {
  auto node = open(0);
  manager::Outbox out;
  node->onRequests({request("t1", transport("t1")), request("t1", "", true), request("zz", "", true),
                    request("t1", "", true)},
                   0, out);
  ASSERT_EQ(out.acks.size(), 4u);
  EXPECT_EQ(out.acks[1].result, msg::AckResult::Stored);
  EXPECT_EQ(out.acks[1].state, msg::TaskState::Cancelled);
  EXPECT_EQ(out.acks[2].result, msg::AckResult::NotFound);
  EXPECT_EQ(out.acks[3].result, msg::AckResult::Refused);
}

TEST(TravelModel, GridDistanceGoesAroundWallsStraightLineDoesNot) {
  // 10×5 cells of 1 m; a wall at x = 5 open only in the top row (y = 4 in the map frame).
  const std::string path = (std::filesystem::temp_directory_path() / "fm_travel.map").string();
  {
    std::ofstream out(path);
    out << "type octile\nheight 5\nwidth 10\nmap\n";
    out << "..........\n";
    for (int r = 0; r < 4; ++r) {
      out << ".....@....\n";
    }
  }
  auto grid = planning::loadMovingAiMap(path, 1.0);
  ASSERT_TRUE(grid) << grid.error().message;
  auto cache =
      std::make_shared<planning::DistanceFieldCache>(std::make_shared<const planning::OccupancyGrid>(*grid));
  StationMap st;
  ASSERT_TRUE(st.add({"P", {7.5, 0.5, 0}, static_cast<std::uint8_t>(StationKind::Pickup)}));
  ASSERT_TRUE(st.add({"D", {7.5, 3.5, 0}, static_cast<std::uint8_t>(StationKind::Dropoff)}));
  Task t;
  t.id = "t";
  t.pickup = "P";
  t.dropoff = "D";
  RobotInfo r;
  r.pose = {2.5, 0.5, 0};
  const double straight = manager::makeTravelModel(st, nullptr, 1.0)(t)(r);
  const double grid_s = manager::makeTravelModel(st, cache, 1.0)(t)(r);
  EXPECT_NEAR(straight, 5.0 + 3.0, 1e-9);
  EXPECT_GT(grid_s, straight + 4.0) << "the wall forces a detour through the top row";
  EXPECT_NEAR(grid_s,
              cache->travelDistance({2.5, 0.5}, {7.5, 0.5}) + cache->travelDistance({7.5, 0.5}, {7.5, 3.5}),
              1e-9);
  std::filesystem::remove(path);
}

namespace {
std::shared_ptr<const site::Site> smallWarehouse() {
  return std::make_shared<const site::Site>(site::loadSite(
      (std::filesystem::path(FLEET_SOURCE_DIR) / "sim/scenarios/small_warehouse.site.json").string()));
}
}  // namespace

// Reserved traffic drives the roadmap: its times (turns, docks' last legs) are the costs.
TEST(TravelModel, RoadmapTimesAreTheRoadmapsDockToDockTimes) {
  const auto site = smallWarehouse();
  const auto roads = std::make_shared<const traffic::RoadmapTravel>(
      std::make_shared<const traffic::Roadmap>(traffic::buildRoadmap(*site)));
  const StationMap st = fleet::stationMapOf(*site);
  Task t;
  t.id = "t";
  t.pickup = "P-1";
  t.dropoff = "D-2";
  RobotInfo atPickup;
  atPickup.pose = site->station("P-1")->pose;
  const auto model = manager::makeRoadmapTravelModel(st, roads);
  EXPECT_NEAR(model(t)(atPickup), *roads->between("P-1", "D-2"), 1e-6);
  RobotInfo atDropoff;
  atDropoff.pose = site->station("D-2")->pose;
  EXPECT_NEAR(model(t)(atDropoff), *roads->between("D-2", "P-1") + *roads->between("P-1", "D-2"), 1e-6);
  // Never below the straight lines at cruise speed: the roadmap is a way through the shelves.
  const double line = (distance(atDropoff.pose.position(), atPickup.pose.position()) * 2) /
                      roads->roadmap().options.cruiseSpeed;
  EXPECT_GT(model(t)(atDropoff), line);
}

namespace {
// A node admitting by the small warehouse's lines with `tasks` transport tasks P-1 → D-1 posted,
// and the places of the shorter of the two lines.
struct ByLines {
  std::shared_ptr<const site::Site> site;
  std::unique_ptr<manager::FleetManagerNode> node;
  std::size_t line = 0;
};
ByLines byLines(manager::Settings settings, int tasks) {
  settings.stationCapacityFromLines = true;
  settings.travelCost = "roadmap";
  ByLines b;
  b.site = smallWarehouse();
  auto n = manager::FleetManagerNode::create(settings, fleet::stationMapOf(*b.site), 1'000, b.site);
  EXPECT_TRUE(n) << n.error().message;
  if (!n) {
    return b;
  }
  b.node = std::move(*n);
  const traffic::RoadmapTravel roads(
      std::make_shared<const traffic::Roadmap>(traffic::buildRoadmap(*b.site)));
  b.line = std::min(roads.lineCapacity("P-1"), roads.lineCapacity("D-1"));
  manager::Outbox out;
  std::vector<msg::Task> reqs;
  for (int i = 0; i < tasks; ++i) {
    reqs.push_back(request("t" + std::to_string(i), transport("t" + std::to_string(i))));
  }
  b.node->onRequests(reqs, 2'000, out);
  return b;
}
}  // namespace

TEST_F(Node, QueueCapacityLetsAsManyTasksAtAStationAsItsLineHolds) {
  const auto b = byLines(settings_, 8);
  ASSERT_TRUE(b.node);
  auto& node = *b.node;
  const auto& site = b.site;
  const std::size_t line = b.line;
  ASSERT_GT(line, 2U) << "the small warehouse's pickups and drop-offs have queues";
  for (int i = 0; i < 8; ++i) {
    const auto& park = site->stations[static_cast<std::size_t>(i)];  // parking places, one robot each
    node.onRobotState({"r" + std::to_string(i),
                       3'000,
                       {park.pose.x, park.pose.y, park.pose.theta},
                       {},
                       0,
                       0,
                       msg::RobotMode::Idle,
                       0.9f,
                       "",
                       0.3f},
                      3'000);
  }
  manager::Outbox assigned;
  node.tick(4'000, assigned);
  EXPECT_EQ(assigned.assignments.size(), line) << "P-1 and D-1 each take as many as their lines hold";
}

// Robots idle while tasks wait for a place in a line, none waiting on another robot: after a
// window of it (30 s) the admission governor widens every line by a quarter (admission_governor.hpp).
TEST_F(Node, IdleRobotsWhileTasksWaitForALineWidenTheLinesAfterAWindow) {
  settings_.reconcileS = 0;  // reconciling off: the robots' activity is still filed
  const auto b = byLines(settings_, 12);
  ASSERT_TRUE(b.node);
  auto& node = *b.node;
  const auto& site = b.site;
  const std::size_t line = b.line;
  std::set<std::string> working;
  constexpr std::int64_t kStep = 200'000'000;  // the manager's 0.2 s tick
  for (std::int64_t t = kStep; t <= 31 * 1'000'000'000LL; t += kStep) {
    for (int i = 0; i < 12; ++i) {
      const std::string id = "r" + std::to_string(i);
      const auto& park = site->stations[static_cast<std::size_t>(i)];
      msg::RobotState s{
          id, t, {park.pose.x, park.pose.y, park.pose.theta}, {}, 0, 0, msg::RobotMode::Idle, 0.9f, "", 0.3f};
      s.activity = working.count(id) > 0 ? RobotActivity::Driving : RobotActivity::NoTask;
      node.onRobotState(s, t);
    }
    manager::Outbox o;
    node.tick(t, o);
    for (const auto& a : o.assignments) {
      working.insert(a.robot_id);
    }
  }
  EXPECT_EQ(node.metricsJson()["admission"]["line_scale"], 1.25);
  EXPECT_GT(node.metricsJson()["admission"]["no_task_share"].get<double>(), 0.5);
  EXPECT_EQ(node.metricsJson()["admission"]["waiting_on_robot_share"], 0.0);
  EXPECT_EQ(working.size(), static_cast<std::size_t>(std::floor(1.25 * static_cast<double>(line))))
      << "a line of " << line << " places admits a quarter more";
}

TEST(Settings, StationCapacityIsANumberOrQueueAndRoadmapCostsNeedASite) {
  auto queue = Config::fromText(R"({"stations": "s.json", "station_capacity": "queue",
                                    "travel_cost": "roadmap", "roadmap": {"queue_length": 2}})",
                                "manager.json");
  const auto s = manager::readSettings(queue);
  queue.finish();
  EXPECT_TRUE(s.stationCapacityFromLines);
  EXPECT_EQ(s.travelCost, "roadmap");
  EXPECT_EQ(s.roadmap.queueLength, 2);
  auto bad = Config::fromText(
      R"({"stations": "s.json", "station_capacity": "lots", "roadmap": {"spacin": 1}})", "manager.json");
  manager::readSettings(bad);
  ASSERT_EQ(bad.problems().size(), 2U);
  EXPECT_THAT(bad.problems()[0] + bad.problems()[1], HasSubstr("station_capacity: expected one of"));
  EXPECT_THAT(bad.problems()[0] + bad.problems()[1], HasSubstr("roadmap.spacin"));
  // Without a site there is no roadmap: a clear refusal, not straight lines in disguise.
  auto noSite = manager::Settings{};
  noSite.travelCost = "roadmap";
  noSite.db =
      (std::filesystem::temp_directory_path() / ("fm_nosite_" + std::to_string(getpid()) + ".db")).string();
  auto n = manager::FleetManagerNode::create(noSite, stations(), 1'000);
  ASSERT_FALSE(n);
  EXPECT_THAT(n.error().message, HasSubstr("needs a site"));
  std::filesystem::remove(noSite.db);
}

TEST(Settings, StationLoadIsTaskPhaseOrArrivalAndArrivalNeedsASite) {
  auto arrival = Config::fromText(R"({"stations": "s.json", "station_load": "arrival"})", "manager.json");
  EXPECT_EQ(manager::readSettings(arrival).stationLoad, StationLoad::Arrival);
  arrival.finish();
  auto bad = Config::fromText(R"({"stations": "s.json", "station_load": "eta"})", "manager.json");
  manager::readSettings(bad);
  ASSERT_EQ(bad.problems().size(), 1U);
  EXPECT_THAT(bad.problems()[0], HasSubstr("station_load: expected one of"));
  auto noSite = manager::Settings{};
  noSite.stationLoad = StationLoad::Arrival;
  noSite.db = (std::filesystem::temp_directory_path() / ("fm_nosite_arr_" + std::to_string(getpid()) + ".db"))
                  .string();
  auto n = manager::FleetManagerNode::create(noSite, stations(), 1'000);
  ASSERT_FALSE(n);
  EXPECT_THAT(n.error().message, HasSubstr("station_load \"arrival\" needs a site"));
  std::filesystem::remove(noSite.db);
}

TEST(Settings, StoreIsSqliteByDefaultOrAPostgresqlUrl) {
  auto defaults = Config::fromText(R"({"stations": "s.json"})", "manager.json");
  auto s = manager::readSettings(defaults);
  defaults.finish();
  EXPECT_EQ(s.store.backend, manager::StoreSettings::Backend::Sqlite);
  EXPECT_EQ(s.db, "fleet.db");
  auto file =
      Config::fromText(R"({"stations": "s.json", "store": "sqlite:/var/lib/fleet/tasks.db"})", "m.json");
  s = manager::readSettings(file);
  file.finish();
  EXPECT_EQ(s.store.backend, manager::StoreSettings::Backend::Sqlite);
  EXPECT_EQ(s.db, "/var/lib/fleet/tasks.db");
  auto pgc = Config::fromText(R"({"stations": "s.json", "lease": {"ttl_s": 4, "renew_s": 0.5},
      "store": "postgresql://fleet@db1:5432,db2:5432/fleet?target_session_attrs=read-write"})",
                              "m.json");
  s = manager::readSettings(pgc);
  pgc.finish();
  EXPECT_EQ(s.store.backend, manager::StoreSettings::Backend::Postgres);
  EXPECT_EQ(s.store.url, "postgresql://fleet@db1:5432,db2:5432/fleet?target_session_attrs=read-write");
  EXPECT_DOUBLE_EQ(s.store.leaseTtlS, 4.0);
  EXPECT_DOUBLE_EQ(s.store.leaseRenewS, 0.5);
  const std::pair<const char*, const char*> bad[] = {
      {R"({"stations": "s.json", "store": "mysql://db/fleet"})", "store: must be"},
      {R"({"stations": "s.json", "store": "postgresql://db:port/fleet"})", "port 'port' is not a number"},
      {R"({"stations": "s.json", "store": "postgresql://db/fleet?target_session_attr=read-write"})",
       "target_session_attr"},
      {R"({"stations": "s.json", "store": "sqlite:a.db", "db": "b.db"})", "give either store or db"},
      {R"({"stations": "s.json", "lease": {"ttl_s": 2, "renew_s": 1.5}})", "at most half of ttl_s"}};
  for (const auto& [text, why] : bad) {
    auto c = Config::fromText(text, "m.json");
    manager::readSettings(c);
    try {
      c.finish();
      ADD_FAILURE() << "accepted " << text;
    } catch (const ConfigError& e) {
      EXPECT_THAT(e.what(), HasSubstr(why)) << text;
    }
  }
}

TEST(Settings, ChargeUntilMustExceedTheBatteryThreshold) {
  auto defaults = Config::fromText(R"({"stations": "s.json"})", "manager.json");
  const auto s = manager::readSettings(defaults);
  defaults.finish();
  EXPECT_DOUBLE_EQ(s.chargeUntil, 0.9);
  EXPECT_DOUBLE_EQ(s.chargeMaxS, 1800.0);
  auto set =
      Config::fromText(R"({"stations": "s.json", "charge_until": 0.8, "charge_max_s": 600})", "m.json");
  EXPECT_DOUBLE_EQ(manager::readSettings(set).chargeUntil, 0.8);
  set.finish();
  for (const char* bad :
       {R"({"stations": "s.json", "battery_threshold": 0.5, "charge_until": 0.5})",
        R"({"stations": "s.json", "charge_until": 1.5})", R"({"stations": "s.json", "charge_max_s": 0})"}) {
    auto c = Config::fromText(bad, "m.json");
    manager::readSettings(c);
    EXPECT_THROW(c.finish(), ConfigError) << bad;
  }
  try {
    auto c = Config::fromText(R"({"stations": "s.json", "battery_threshold": 0.5, "charge_until": 0.4})",
                              "m.json");
    manager::readSettings(c);
    c.finish();
    ADD_FAILURE() << "accepted charge_until below battery_threshold";
  } catch (const ConfigError& e) {
    EXPECT_THAT(e.what(), HasSubstr("charge_until: must be greater than battery_threshold (0.5), got 0.4"));
  }
}

// The charge goal asks the robot to dwell (charge_max_s at most); the manager ends the task when
// The robot's RobotState at the charger shows charge_until, and tells the robot with an empty order.
TEST_F(Node, ChargeTaskDwellsUntilTheManagerSeesTheTargetBattery) {
  settings_.chargeMaxS = 900.0;
  auto node = open(0);
  manager::Outbox out;
  node->onRobotState({"r1", 1'000, {3, 1, 0}, {}, 0, 0, msg::RobotMode::Idle, 0.1f, "", 0.3f}, 1'000);
  node->tick(2'000, out);
  ASSERT_EQ(out.assignments.size(), 1u);
  const auto a = out.assignments[0];
  ASSERT_EQ(a.goals.size(), 1u);
  EXPECT_EQ(a.goals[0].station, "C-1");
  EXPECT_EQ(a.goals[0].action, msg::GoalAction::Charge);
  EXPECT_DOUBLE_EQ(a.goals[0].duration_s, 900.0);
  out = {};
  node->onStatus({"r1", a.task_id, a.revision, msg::TaskState::EnRoute, 0.0f, "", 3'000}, 3'000, out);
  std::int64_t now = 4'000;
  for (float b = 0.1f; b < 0.895f; b += 0.01f, now += 200'000'000) {
    node->onRobotState({"r1", now, {0.05, 0, 0}, {}, 0, 0, msg::RobotMode::Charging, b, a.task_id, 0.3f},
                       now);
    node->tick(now, out);
  }
  EXPECT_TRUE(out.assignments.empty()) << "charging: no new order, no second charge task";
  node->onRobotState({"r1", now, {0.05, 0, 0}, {}, 0, 0, msg::RobotMode::Charging, 0.9f, a.task_id, 0.3f},
                     now);
  node->tick(now, out);
  ASSERT_FALSE(out.events.empty());
  EXPECT_EQ(out.events.back().task_id, a.task_id);
  EXPECT_EQ(out.events.back().state, msg::TaskState::Done);
  ASSERT_EQ(out.assignments.size(), 1u);
  EXPECT_EQ(out.assignments[0].robot_id, "r1");
  EXPECT_TRUE(out.assignments[0].task_id.empty()) << "released from the charger";
  EXPECT_GT(out.assignments[0].revision, a.revision);
  EXPECT_EQ(node->dispatcher().counters().submitted, 1);
}

TEST(Settings, TravelCostIsPathByDefaultAndStraightOnRequest) {
  auto defaults = Config::fromText(R"({"stations": "s.json"})", "manager.json");
  EXPECT_EQ(manager::readSettings(defaults).travelCost, "path");
  auto straight = Config::fromText(R"({"stations": "s.json", "travel_cost": "straight"})", "manager.json");
  EXPECT_EQ(manager::readSettings(straight).travelCost, "straight");
  auto bad =
      Config::fromText(R"({"stations": "s.json", "travel_cost": "as the crow flies"})", "manager.json");
  manager::readSettings(bad);
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.problems()[0].find("manager.json: travel_cost: expected one of"), std::string::npos)
      << bad.problems()[0];
}

// Leases used the robot's own stamp, so a robot whose clock ran 1.5 s behind was lost
// at once and never got a task (and one stamping INT64_MAX was never lost). The lease now runs on
// The manager's clock, from when the state was received.
TEST_F(Node, LeaseRunsOnTheManagersClockNotTheRobots) {
  settings_.leaseS = 1.0;
  auto node = open(0);
  manager::Outbox out;
  const std::int64_t now = 10'000'000'000;
  node->onRequests({request("t1", transport("t1"))}, now, out);
  // r1's clock is 1.5 s behind the manager's; r2 stamps the largest stamp there is.
  node->onRobotState({"r1", now - 1'500'000'000, {0, 1, 0}, {}, 0, 0, msg::RobotMode::Idle, 0.9f, "", 0.3f},
                     now);
  node->onRobotState({"r2", INT64_MAX, {40, 1, 0}, {}, 0, 0, msg::RobotMode::Idle, 0.9f, "", 0.3f}, now);
  out = {};
  node->tick(now + 100'000'000, out);
  ASSERT_EQ(out.assignments.size(), 1u) << "a robot with a late clock still gets work";
  EXPECT_EQ(out.assignments[0].robot_id, "r1");
  // Both fall silent: both are lost after the lease, whatever they stamped.
  out = {};
  node->tick(now + 2'000'000'000, out);
  EXPECT_EQ(node->dispatcher().robots().onlineCount(), 0u);
}

// After a restart the manager announces every open task's state, with the seq
// going on from the task's stored revision (an adapter that kept running sees no step back).
TEST_F(Node, RestartAnnouncesEveryOpenTaskAsAnEvent) {
  {
    auto node = open(0);
    manager::Outbox out;
    node->onRequests({request("t1", transport("t1")), request("t2", transport("t2"))}, 0, out);
    node->onRobotState({"r1", 0, {0, 1, 0}, {}, 0, 0, msg::RobotMode::Idle, 0.9f, "", 0.3f}, 0);
    node->tick(1, out);
  }
  auto node = open(10);
  std::map<std::string, msg::TaskEvent> events;
  for (const auto& e : node->recovered().events) {
    events[e.task_id] = e;
  }
  ASSERT_EQ(events.size(), 2u);
  const auto& assigned = events.begin()->second.state == msg::TaskState::Assigned ? events.begin()->second
                                                                                  : events.rbegin()->second;
  EXPECT_EQ(assigned.state, msg::TaskState::Assigned);
  EXPECT_EQ(assigned.robot_id, "r1");
  EXPECT_EQ(assigned.seq, 2u) << "queued (1), assigned (2)";
  manager::Outbox out;
  node->onStatus({"r1", assigned.task_id, node->recovered().assignments[0].revision, msg::TaskState::EnRoute,
                  0.1f, "", 20},
                 20, out);
  ASSERT_FALSE(out.events.empty());
  EXPECT_EQ(out.events.back().seq, 3u);
}

// The adapter asks for a task its view lacks; the manager answers from the store,
// finished tasks included.
TEST_F(Node, QueryAnswersFromTheStore) {
  auto node = open(0);
  manager::Outbox out;
  node->onRequests({request("t1", transport("t1"))}, 0, out);
  node->onRequests({request("t1", "", true)}, 1, out);  // cancelled: no longer open
  msg::Task q;
  q.task_id = "t1";
  q.request_id = "q-1";
  q.control = msg::TaskControl::Query;
  msg::Task missing = q;
  missing.task_id = "nope";
  missing.request_id = "q-2";
  out = {};
  node->onRequests({q, missing}, 2, out);
  ASSERT_EQ(out.acks.size(), 2u);
  EXPECT_EQ(out.acks[0].result, msg::AckResult::Stored);
  EXPECT_EQ(out.acks[0].state, msg::TaskState::Cancelled);
  const auto d = nlohmann::json::parse(out.acks[0].detail);
  EXPECT_EQ(d["task"]["pickup"], "P-1");
  EXPECT_EQ(d["reason"], "cancelled by request");
  EXPECT_EQ(out.acks[1].result, msg::AckResult::NotFound);
  EXPECT_TRUE(out.events.empty()) << "a query changes nothing";
}

namespace {
msg::Task robotControl(const std::string& robot, msg::TaskControl c) {
  msg::Task t;
  t.task_id = robot;
  t.robot = robot;
  t.request_id = "req-" + std::to_string(++gRequest);
  t.control = c;
  return t;
}
}  // namespace

TEST_F(Node, AHeldRobotGetsNoTaskAndStandsStillUntilReleased) {
  auto node = open(0);
  manager::Outbox out;
  node->onRobotState({"r1", 0, {0, 1, 0}, {}, 0, 0, msg::RobotMode::Idle, 0.9f, "", 0.3f}, 0);
  node->onRequests(
      {robotControl("r1", msg::TaskControl::HoldRobot), robotControl("r9", msg::TaskControl::HoldRobot)}, 0,
      out);
  ASSERT_EQ(out.acks.size(), 2u);
  EXPECT_EQ(out.acks[0].result, msg::AckResult::Stored);
  EXPECT_EQ(out.acks[1].result, msg::AckResult::NotFound) << "a robot never seen";
  ASSERT_EQ(out.assignments.size(), 1u) << "the idle robot is told to hold where it is";
  EXPECT_EQ(out.assignments[0].robot_id, "r1");
  EXPECT_TRUE(out.assignments[0].task_id.empty());
  EXPECT_TRUE(out.assignments[0].paused);
  out = {};
  node->onRequests({request("t1", transport("t1"))}, 1'000, out);
  out = {};
  node->tick(100'000'000, out);
  EXPECT_TRUE(out.assignments.empty()) << "a held robot was given a task";
  node->onRequests({robotControl("r1", msg::TaskControl::ReleaseRobot)}, 200'000'000, out);
  node->tick(300'000'000, out);
  ASSERT_FALSE(out.assignments.empty());
  EXPECT_EQ(out.assignments.back().task_id, "t1");
  EXPECT_FALSE(out.assignments.back().paused);
}

TEST_F(Node, HoldingABusyRobotPausesItsTaskAndReleasingResumesIt) {
  auto node = open(0);
  manager::Outbox out;
  node->onRequests({request("t1", transport("t1"))}, 0, out);
  node->onRobotState({"r1", 0, {0, 1, 0}, {}, 0, 0, msg::RobotMode::Idle, 0.9f, "", 0.3f}, 0);
  node->tick(100'000'000, out);
  out = {};
  node->onRequests({robotControl("r1", msg::TaskControl::HoldRobot)}, 200'000'000, out);
  ASSERT_EQ(out.acks.size(), 1u);
  EXPECT_EQ(out.acks[0].detail, "t1") << "the ack names the robot's task";
  ASSERT_EQ(out.assignments.size(), 1u);
  EXPECT_EQ(out.assignments[0].task_id, "t1");
  EXPECT_TRUE(out.assignments[0].paused);
  out = {};
  node->onRequests({robotControl("r1", msg::TaskControl::ReleaseRobot)}, 300'000'000, out);
  ASSERT_EQ(out.assignments.size(), 1u);
  EXPECT_EQ(out.assignments[0].task_id, "t1");
  EXPECT_FALSE(out.assignments[0].paused);
}

namespace {
/// Parking places K-1..K-3 along y = 10 and one charger; nothing at the origin.
StationMap parkingSite(bool withK3 = true) {
  StationMap m;
  EXPECT_TRUE(m.add({"P-1", {1, 1, 0}, static_cast<std::uint8_t>(StationKind::Pickup)}));
  EXPECT_TRUE(m.add({"D-1", {5, 1, 0}, static_cast<std::uint8_t>(StationKind::Dropoff)}));
  EXPECT_TRUE(m.add({"K-1", {10, 10, 0}, static_cast<std::uint8_t>(StationKind::Parking)}));
  EXPECT_TRUE(m.add({"K-2", {20, 10, 0}, static_cast<std::uint8_t>(StationKind::Parking)}));
  if (withK3) {
    EXPECT_TRUE(m.add({"K-3", {30, 10, 0}, static_cast<std::uint8_t>(StationKind::Parking)}));
  }
  EXPECT_TRUE(m.add({"C-1", {15, -10, 0}, static_cast<std::uint8_t>(StationKind::Charging)}));
  return m;
}

msg::RobotState idleAt(const std::string& id, double x, double y, std::int64_t t, float battery = 0.9f) {
  return {id, t, {x, y, 0}, {}, 0, 0, msg::RobotMode::Idle, battery, "", 0.3f};
}

void expectNoGoalAtTheOrigin(const manager::Outbox& out) {
  for (const auto& a : out.assignments) {
    for (const auto& g : a.goals) {
      EXPECT_FALSE(g.pose.x == 0 && g.pose.y == 0) << a.task_id << " sends " << a.robot_id << " to (0, 0)";
      EXPECT_FALSE(g.station.empty()) << a.task_id;
    }
  }
}
}  // namespace

TEST_F(Node, ParkAndChargeTasksWithoutAStationGoToTheNearestFreeOneAndKeepItAcrossARestart) {
  settings_.travelCost = "straight";
  std::string park1Station;
  {
    auto node = open(0, parkingSite());
    manager::Outbox out;
    node->onRobotState(idleAt("r1", 19, 0, 0), 0);
    node->onRobotState(idleAt("r2", 21, 0, 0), 0);
    node->onRobotState(idleAt("r3", 15, -7, 0), 0);
    node->onRequests({request("park-1", R"({"id": "park-1", "kind": "park"})"),
                      request("park-2", R"({"id": "park-2", "kind": "park"})"),
                      request("charge-1", R"({"id": "charge-1", "kind": "charge"})")},
                     1'000, out);
    ASSERT_EQ(out.acks.size(), 3u);
    for (const auto& a : out.acks) {
      EXPECT_EQ(a.result, msg::AckResult::Stored) << a.detail;
    }
    out = {};
    node->tick(2'000, out);
    expectNoGoalAtTheOrigin(out);
    ASSERT_EQ(out.assignments.size(), 3u);
    std::map<std::string, msg::Goal> goalOf;
    for (const auto& a : out.assignments) {
      ASSERT_EQ(a.goals.size(), 1u);
      goalOf[a.task_id] = a.goals[0];
    }
    EXPECT_EQ(goalOf["charge-1"].station, "C-1");
    EXPECT_EQ(goalOf["charge-1"].action, msg::GoalAction::Charge);
    EXPECT_NE(goalOf["park-1"].station, goalOf["park-2"].station) << "two robots sent to one place";
    EXPECT_TRUE(goalOf["park-1"].station == "K-2" || goalOf["park-2"].station == "K-2");
    EXPECT_EQ(goalOf["park-1"].action, msg::GoalAction::Park);
    EXPECT_DOUBLE_EQ(goalOf["park-1"].pose.y, 10.0);
    park1Station = goalOf["park-1"].station;
    // The assigned events name the chosen station.
    std::map<std::string, std::string> eventStation;
    for (const auto& e : out.events) {
      if (e.state == msg::TaskState::Assigned) {
        eventStation[e.task_id] = e.station;
      }
    }
    EXPECT_EQ(eventStation["park-1"], park1Station);
    EXPECT_EQ(eventStation["charge-1"], "C-1");
  }
  auto node = open(10'000, parkingSite());  // the manager restarts
  expectNoGoalAtTheOrigin(node->recovered());
  std::map<std::string, std::string> recovered;
  for (const auto& a : node->recovered().assignments) {
    ASSERT_EQ(a.goals.size(), 1u);
    recovered[a.task_id] = a.goals[0].station;
  }
  EXPECT_EQ(recovered["park-1"], park1Station) << "the choice is durable";
  EXPECT_EQ(recovered["charge-1"], "C-1");
  for (const auto& e : node->recovered().events) {
    if (e.task_id == "park-1") {
      EXPECT_EQ(e.station, park1Station);
    }
  }
  // GET /v1/tasks/park-1 through the adapter asks the manager: the stored task shows the station.
  msg::Task q;
  q.task_id = "park-1";
  q.request_id = "q-park";
  q.control = msg::TaskControl::Query;
  manager::Outbox out;
  node->onRequests({q}, 11'000, out);
  ASSERT_EQ(out.acks.size(), 1u);
  const auto d = nlohmann::json::parse(out.acks[0].detail);
  EXPECT_EQ(d["task"]["station"], park1Station);
  EXPECT_EQ(d["station_chosen"], true);
}

TEST_F(Node, AStationlessParkTaskIsRefusedOnASiteWithoutParking) {
  auto node = open(0, [] {
    StationMap m;
    EXPECT_TRUE(m.add({"P-1", {1, 1, 0}, static_cast<std::uint8_t>(StationKind::Pickup)}));
    EXPECT_TRUE(m.add({"C-1", {3, 3, 0}, static_cast<std::uint8_t>(StationKind::Charging)}));
    return m;
  }());
  manager::Outbox out;
  node->onRequests({request("park-1", R"({"id": "park-1", "kind": "park"})")}, 0, out);
  ASSERT_EQ(out.acks.size(), 1u);
  EXPECT_EQ(out.acks[0].result, msg::AckResult::Invalid);
  EXPECT_THAT(out.acks[0].detail, HasSubstr(R"("path":"station")"));
  EXPECT_THAT(out.acks[0].detail, HasSubstr("no parking station on this site to choose from"));
  EXPECT_TRUE(out.events.empty()) << "nothing stored";
}

// A station that is not on the site (a stored task's station removed from the site before a
// restart) must never become a goal at (0, 0): the task fails with the reason, the robot is freed.
TEST_F(Node, AnOrderWhoseStationIsNotOnTheSiteFailsTheTaskInsteadOfDrivingToTheOrigin) {
  settings_.travelCost = "straight";
  {
    auto node = open(0, parkingSite());
    manager::Outbox out;
    node->onRobotState(idleAt("r1", 29, 0, 0), 0);
    node->onRequests({request("park-1", R"({"id": "park-1", "kind": "park", "station": "K-3"})")}, 1'000,
                     out);
    node->tick(2'000, out);
    ASSERT_EQ(out.assignments.size(), 1u);
    ASSERT_EQ(out.assignments[0].goals.at(0).station, "K-3");
  }
  auto node = open(10'000, parkingSite(false));  // K-3 is gone from the site
  const auto& rec = node->recovered();
  expectNoGoalAtTheOrigin(rec);
  ASSERT_EQ(rec.assignments.size(), 1u);
  EXPECT_EQ(rec.assignments[0].robot_id, "r1");
  EXPECT_TRUE(rec.assignments[0].task_id.empty()) << "the robot gets an empty order, not (0, 0)";
  ASSERT_FALSE(rec.events.empty());
  const auto& last = rec.events.back();
  EXPECT_EQ(last.task_id, "park-1");
  EXPECT_EQ(last.state, msg::TaskState::Failed);
  EXPECT_THAT(last.reason, HasSubstr("station 'K-3', which is not on this site"));
  EXPECT_EQ(last.seq, rec.events.front().seq + 1) << "the failure follows the announced state";
  EXPECT_TRUE(node->dispatcher().openTasks().empty());
  EXPECT_EQ(node->metricsJson()["bad_orders"], 1);
}

// A station closed at run time (an operator's roadmap closure over its dock, as the WMS adapter
// sends it): the waiting task that needs it is held with a stated reason and no ETA, while a task
// elsewhere is assigned; a closure naming a node not on the roadmap is refused and changes
// nothing; once lifted the held task is assigned.
TEST_F(Node, AClosureOverAStationHoldsItsWaitingTasksWithTheReasonUntilLifted) {
  const auto site = smallWarehouse();
  auto n = manager::FleetManagerNode::create(settings_, fleet::stationMapOf(*site), 1'000, site);
  ASSERT_TRUE(n) << n.error().message;
  auto& node = **n;
  manager::Outbox out;
  node.onRequests(
      {request("to-d1", transport("to-d1")),
       request("to-d2", R"({"id": "to-d2", "kind": "transport", "pickup": "P-2", "dropoff": "D-2"})")},
      2'000, out);
  const Pose2 d1 = site->station("D-1")->pose;
  msg::TrafficClosure spill;
  spill.closure_id = "spill";
  spill.reason = "wet floor";
  spill.area = {
      {d1.x - 0.6, d1.y - 0.6}, {d1.x + 0.6, d1.y - 0.6}, {d1.x + 0.6, d1.y + 0.6}, {d1.x - 0.6, d1.y + 0.6}};
  msg::TrafficClosure bad;
  bad.closure_id = "bad";
  bad.nodes = {1'000'000};
  out = {};
  const auto errors = node.onClosures({spill, bad}, 3'000, out);
  ASSERT_EQ(errors.size(), 1u);
  EXPECT_NE(errors[0].find("node 1000000 is not on the roadmap"), std::string::npos) << errors[0];
  ASSERT_EQ(node.dispatcher().closedStations().count("D-1"), 1u);
  EXPECT_EQ(node.dispatcher().closedStations().count("D-2"), 0u);
  ASSERT_EQ(out.events.size(), 1u);
  EXPECT_EQ(out.events[0].task_id, "to-d1");
  EXPECT_EQ(out.events[0].reason, "station D-1 closed: closure 'spill': wet floor");
  EXPECT_EQ(out.events[0].eta_ns, 0);

  const auto& park = site->stations.front();
  node.onRobotState({"r1",
                     4'000,
                     {park.pose.x, park.pose.y, park.pose.theta},
                     {},
                     0,
                     0,
                     msg::RobotMode::Idle,
                     0.9f,
                     "",
                     0.3f},
                    4'000);
  out = {};
  node.tick(5'000, out);
  ASSERT_EQ(out.assignments.size(), 1u);
  EXPECT_EQ(out.assignments[0].task_id, "to-d2") << "the task to the closed station waits";

  spill.active = false;
  out = {};
  EXPECT_TRUE(node.onClosures({spill}, 6'000, out).empty());
  EXPECT_TRUE(node.dispatcher().closedStations().empty());
  ASSERT_EQ(out.events.size(), 1u);
  EXPECT_EQ(out.events[0].reason, "station D-1 open again; waiting for a robot");
}
