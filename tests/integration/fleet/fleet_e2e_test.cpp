// The fleet manager and the WMS adapter as separate processes, with this test playing the robots
// over DDS: tasks posted over HTTP reach a robot, progress to done, survive a kill -9 of the
// manager, and nothing acknowledged is lost or duplicated.

#include <gtest/gtest.h>
#include <httplib.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <random>
#include <set>
#include <thread>

#include "fake_robots.hpp"
#include "fleet/core/clock.hpp"
#include "fleet/transport/dds.hpp"
#include "test_process.hpp"

using namespace fleet;
using namespace std::chrono_literals;
using nlohmann::json;
using Clk = std::chrono::steady_clock;
using test::FakeRobots;

namespace {

class FleetE2E : public ::testing::Test {
 protected:
  void SetUp() override {
    domain_ = std::to_string(test::uniqueDomain());
    setenv("FLEET_DDS_DOMAIN", domain_.c_str(), 1);
    dir_ = std::filesystem::temp_directory_path() / ("fleet_e2e_" + domain_);
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
    std::ofstream(dir_ / "stations.json") << R"({"stations": [
      {"name": "P-1", "x": 2, "y": 1, "kinds": ["pickup"]},
      {"name": "P-2", "x": 2, "y": 4, "kinds": ["pickup"]},
      {"name": "D-1", "x": 8, "y": 1, "kinds": ["dropoff"]},
      {"name": "C-1", "x": 0, "y": 0, "kinds": ["charging", "parking"]}]})";
    std::ofstream(dir_ / "manager.json") << json{
        {"db", (dir_ / "fleet.db").string()},
        {"stations", (dir_ / "stations.json").string()},
        {"tick_s", 0.05},
        {"lease_s", 2.0},
        {"sync", "normal"}}.dump();
    port_ = test::freePort();
    startManager();
    startAdapter();
    http_ = std::make_unique<httplib::Client>("127.0.0.1", port_);
    http_->set_read_timeout(10, 0);
    waitHealthy();
  }
  void TearDown() override {
    adapter_.reset();
    manager_.reset();
    std::filesystem::remove_all(dir_);
  }
  void startManager() {
    manager_ = std::make_unique<test::ChildProcess>(
        FLEET_BINARY_DIR "/services/fleet_manager/fleet_manager",
        std::vector<std::string>{"--config", (dir_ / "manager.json").string(), "--log-level", "warn"},
        std::vector<std::pair<std::string, std::string>>{{"FLEET_DDS_DOMAIN", domain_}});
  }
  void startAdapter() {
    adapter_ = std::make_unique<test::ChildProcess>(
        FLEET_BINARY_DIR "/services/wms_adapter/wms_adapter",
        std::vector<std::string>{"--stations", (dir_ / "stations.json").string(), "--port",
                                 std::to_string(port_), "--log-level", "warn"},
        std::vector<std::pair<std::string, std::string>>{{"FLEET_DDS_DOMAIN", domain_}});
  }
  void waitHealthy() {
    const auto end = Clk::now() + 20s;
    while (Clk::now() < end) {
      auto r = http_->Get("/v1/health");
      if (r && r->status == 200) {
        return;
      }
      std::this_thread::sleep_for(50ms);
    }
    FAIL() << "the adapter never saw the manager";
  }
  json getTask(const std::string& id) {
    auto r = http_->Get("/v1/tasks/" + id);
    return r && r->status == 200 ? json::parse(r->body) : json{};
  }

  std::string domain_;
  std::filesystem::path dir_;
  int port_ = 0;
  std::unique_ptr<test::ChildProcess> manager_;
  std::unique_ptr<test::ChildProcess> adapter_;
  std::unique_ptr<httplib::Client> http_;
};

}  // namespace

TEST_F(FleetE2E, PostedTaskReachesARobotAndIsDone) {
  transport::Participant p;
  FakeRobots robots(p, 2);
  auto r =
      http_->Post("/v1/tasks", R"({"id": "job-1", "kind": "transport", "pickup": "P-1", "dropoff": "D-1"})",
                  "application/json");
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 201) << r->body;
  const auto end = Clk::now() + 20s;
  while (Clk::now() < end && getTask("job-1").value("state", "") != "done") {
    robots.publishStates();
    robots.work();
    std::this_thread::sleep_for(50ms);
  }
  const auto t = getTask("job-1");
  EXPECT_EQ(t.value("state", ""), "done");
  ASSERT_FALSE(robots.received.empty());
  EXPECT_EQ(robots.received[0].goals.size(), 2u);
  EXPECT_EQ(robots.received[0].goals[0].station, "P-1");
  // The same POST again is idempotent; a different body with the same id is a conflict.
  r = http_->Post("/v1/tasks", R"({"id": "job-1", "kind": "transport", "pickup": "P-1", "dropoff": "D-1"})",
                  "application/json");
  EXPECT_EQ(r->status, 200);
  EXPECT_EQ(json::parse(r->body)["state"], "done");
  r = http_->Post("/v1/tasks", R"({"id": "job-1", "kind": "transport", "pickup": "P-2", "dropoff": "D-1"})",
                  "application/json");
  EXPECT_EQ(r->status, 409);
}

// A three-stop task over HTTP: checked against the site by the adapter (a bad step is a 400 naming
// it), sent with its steps to the manager, ordered to a robot as one goal a stop with the load ids,
// and followed stop by stop (GET shows the stop) until done.
TEST_F(FleetE2E, AThreeStopTaskIsOrderedStopByStopAndDone) {
  transport::Participant p;
  FakeRobots robots(p, 1);
  auto r = http_->Post("/v1/tasks", R"({"id": "multi-bad", "steps": [
      {"action": "pick", "station": "P-1", "load_id": "L-1"},
      {"action": "drop", "station": "P-2", "load_id": "L-1"}]})",
                       "application/json");
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 400) << r->body;
  const auto bad = json::parse(r->body);
  ASSERT_EQ(bad["fields"].size(), 1u) << r->body;
  EXPECT_EQ(bad["fields"][0]["path"], "steps[1].station");
  EXPECT_EQ(bad["fields"][0]["reason"], "station 'P-2' is not a dropoff station");
  r = http_->Post("/v1/tasks", R"({"id": "multi-1", "kind": "multistop", "steps": [
      {"action": "pick", "station": "P-1", "load_id": "L-1"},
      {"action": "drop", "station": "D-1", "load_id": "L-1"},
      {"action": "goto", "station": "C-1"}]})",
                  "application/json");
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 201) << r->body;
  std::optional<msg::TaskAssignment> order;
  const auto end = Clk::now() + 20s;
  while (Clk::now() < end && !order) {
    robots.publishStates();
    for (auto& a : robots.orders.take()) {
      if (a.task_id == "multi-1") {
        order = a;
      }
    }
    std::this_thread::sleep_for(50ms);
  }
  ASSERT_TRUE(order) << "no order for the task";
  ASSERT_EQ(order->goals.size(), 3u);
  EXPECT_EQ(order->goals[0].station, "P-1");
  EXPECT_EQ(order->goals[0].action, msg::GoalAction::Load);
  EXPECT_EQ(order->goals[0].load_id, "L-1");
  EXPECT_EQ(order->goals[1].action, msg::GoalAction::Unload);
  EXPECT_EQ(order->goals[1].load_id, "L-1");
  EXPECT_EQ(order->goals[2].station, "C-1");
  auto report = [&](msg::TaskState st, std::uint32_t step) {
    robots.statuses.write(
        {order->robot_id, "multi-1", order->revision, st, 0.0f, "", WallClock().nowNs(), step});
  };
  // The view of the task until `pred` holds (at most 10 s).
  auto viewUntil = [&](const std::function<bool(const json&)>& pred) {
    json t;
    const auto until = Clk::now() + 10s;
    while (Clk::now() < until && !pred(t = getTask("multi-1"))) {
      robots.publishStates();
      std::this_thread::sleep_for(50ms);
    }
    return t;
  };
  report(msg::TaskState::EnRoute, 1);
  report(msg::TaskState::Loading, 1);
  report(msg::TaskState::Delivering, 2);
  auto t = viewUntil([](const json& v) { return v.value("step", 0) == 2; });
  EXPECT_EQ(t.value("step", 0), 2) << t.dump();
  EXPECT_EQ(t.value("state", ""), "en_route") << t.dump();
  EXPECT_EQ(t.value("reason", ""), "step 2 of 3: drop L-1 at D-1");
  ASSERT_TRUE(t.contains("task"));
  EXPECT_EQ(t["task"]["steps"].size(), 3u);
  report(msg::TaskState::Unloading, 2);
  report(msg::TaskState::Delivering, 3);
  report(msg::TaskState::Done, 3);
  t = viewUntil([](const json& v) { return v.value("state", "") == "done"; });
  EXPECT_EQ(t.value("state", ""), "done") << t.dump();
  EXPECT_EQ(t.value("step", 0), 3);
}

TEST_F(FleetE2E, KillNineUnderLoadLosesNothingAcknowledged) {
  // Clients post batches while the manager is killed with SIGKILL at random moments and
  // restarted. Every task that got a 2xx must be in the store afterwards, exactly once.
  std::mt19937 rng(42);
  std::set<std::string> acknowledged;
  int next = 0;
  for (int round = 0; round < 3; ++round) {
    std::atomic<bool> stop{false};
    std::thread client([&] {
      httplib::Client c("127.0.0.1", port_);
      c.set_read_timeout(10, 0);
      while (!stop) {
        json batch = json::array();
        std::vector<std::string> ids;
        for (int k = 0; k < 20; ++k) {
          ids.push_back("load-" + std::to_string(next++));
          batch.push_back({{"id", ids.back()}, {"kind", "goto"}, {"station", "D-1"}});
        }
        auto r = c.Post("/v1/tasks", batch.dump(), "application/json");
        if (r && (r->status == 200 || r->status == 201 || r->status == 207)) {
          const json body = json::parse(r->body);
          for (const auto& item : body["results"]) {
            if (item["status"] == 201 || item["status"] == 200) {
              acknowledged.insert(item["id"].get<std::string>());
            }
          }
        }
      }
    });
    std::this_thread::sleep_for(std::chrono::milliseconds(200 + rng() % 600));
    manager_->kill(SIGKILL);
    stop = true;
    client.join();
    startManager();
    waitHealthy();
  }
  ASSERT_GT(acknowledged.size(), 20u);
  // Re-posting every acknowledged task must find it stored (200 duplicate, never 201).
  int missing = 0;
  for (const auto& id : acknowledged) {
    auto r = http_->Post("/v1/tasks", json{{"id", id}, {"kind", "goto"}, {"station", "D-1"}}.dump(),
                         "application/json");
    ASSERT_TRUE(r);
    if (r->status != 200) {
      ++missing;
      ADD_FAILURE() << id << " was acknowledged but is not stored (status " << r->status << ")";
      if (missing > 5) {
        break;
      }
    }
  }
  EXPECT_EQ(missing, 0) << "of " << acknowledged.size() << " acknowledged tasks";
}

TEST_F(FleetE2E, RobotWhoseAgentEndsIsLostAtOnceByLiveliness) {
  // A long state lease, so only DDS liveliness can explain a quick re-queue.
  manager_->kill(SIGKILL);
  std::ofstream(dir_ / "manager.json") << json{
      {"db", (dir_ / "fleet.db").string()},
      {"stations", (dir_ / "stations.json").string()},
      {"tick_s", 0.05},
      {"lease_s", 30.0},
      {"sync", "normal"}}.dump();
  startManager();
  waitHealthy();
  auto agentProcess = std::make_unique<transport::Participant>();  // plays one agent process
  FakeRobots doomed(*agentProcess, 1);
  transport::Participant observer;
  transport::Reader<msg::TaskEvent> events(observer);
  auto r =
      http_->Post("/v1/tasks", R"({"id": "job-live", "kind": "goto", "station": "D-1"})", "application/json");
  ASSERT_EQ(r->status, 201);
  // The robot takes the task but never finishes it.
  const auto end = Clk::now() + 20s;
  while (Clk::now() < end && doomed.received.empty()) {
    doomed.publishStates();
    for (auto& a : doomed.orders.take()) {
      if (!a.task_id.empty()) {
        doomed.received.push_back(a);
      }
    }
    std::this_thread::sleep_for(50ms);
  }
  ASSERT_FALSE(doomed.received.empty());
  (void)events.take();
  const auto t0 = Clk::now();
  agentProcess.reset();  // the agent process ends: its writers disappear
  bool requeued = false;
  while (!requeued && Clk::now() - t0 < 10s) {
    events.waitForData(100ms);
    for (const auto& e : events.take()) {
      requeued = requeued || (e.task_id == "job-live" && e.state == msg::TaskState::Requeued);
    }
  }
  EXPECT_TRUE(requeued);
  EXPECT_LT(Clk::now() - t0, 5s) << "re-queued by liveliness, well before the 30 s state lease";
}

TEST_F(FleetE2E, PauseOverHttpHoldsTheRobotAndSurvivesAManagerKill) {
  transport::Participant p;
  FakeRobots robots(p, 1);
  ASSERT_EQ(
      http_
          ->Post("/v1/tasks", R"({"id": "job-p", "kind": "transport", "pickup": "P-1", "dropoff": "D-1"})",
                 "application/json")
          ->status,
      201);
  // Orders the robot gets, without finishing them (it is driving).
  std::vector<msg::TaskAssignment> got;
  auto waitFor = [&](auto pred, std::chrono::seconds limit) {
    const auto end = Clk::now() + limit;
    while (Clk::now() < end) {
      robots.publishStates();
      for (auto& a : robots.orders.take()) {
        got.push_back(a);
        if (!a.task_id.empty()) {
          robots.current[a.robot_id] = a;
        }
        if (pred(a)) {
          return true;
        }
      }
      std::this_thread::sleep_for(50ms);
    }
    return false;
  };
  ASSERT_TRUE(waitFor([](const msg::TaskAssignment& a) { return a.task_id == "job-p" && !a.paused; }, 10s));
  auto r = http_->Post("/v1/tasks/job-p/pause", "", "application/json");
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 200) << r->body;
  EXPECT_EQ(json::parse(r->body)["paused"], true);
  ASSERT_TRUE(waitFor([](const msg::TaskAssignment& a) { return a.task_id == "job-p" && a.paused; }, 10s));
  // The hold is durable: a restarted manager re-sends the order still paused.
  got.clear();
  manager_->kill(SIGKILL);
  manager_->wait(5s);
  startManager();
  ASSERT_TRUE(waitFor([](const msg::TaskAssignment& a) { return a.task_id == "job-p"; }, 15s));
  EXPECT_TRUE(got.back().paused) << "the restarted manager lost the pause";
  waitHealthy();
  r = http_->Post("/v1/tasks/job-p/resume", "", "application/json");
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 200) << r->body;
  ASSERT_TRUE(waitFor([](const msg::TaskAssignment& a) { return a.task_id == "job-p" && !a.paused; }, 10s));
  robots.work();  // drives on and delivers
  const auto end = Clk::now() + 10s;
  while (Clk::now() < end && getTask("job-p").value("state", "") != "done") {
    robots.publishStates();
    std::this_thread::sleep_for(50ms);
  }
  EXPECT_EQ(getTask("job-p").value("state", ""), "done");
}

// PATCH /v1/tasks/{id} through the real adapter and manager: the change is stored (it outlives a
// manager kill), comes back as a task event into the adapter's view, decides which task the one
// robot gets first, and is refused with 409 naming the state once the task is assigned.
TEST_F(FleetE2E, ChangeOverHttpReordersTheQueueAndIsRefusedOnceAssigned) {
  for (const auto* body :
       {R"({"id": "job-a", "kind": "transport", "pickup": "P-1", "dropoff": "D-1", "priority": 5})",
        R"({"id": "job-b", "kind": "transport", "pickup": "P-1", "dropoff": "D-1"})"}) {
    ASSERT_EQ(http_->Post("/v1/tasks", body, "application/json")->status, 201);
  }
  auto r = http_->Patch("/v1/tasks/job-b", R"({"priority": 50, "deadline": "2100-01-01T00:00:00Z"})",
                        "application/json");
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 200) << r->body;
  const json changed = json::parse(r->body, nullptr, false);
  EXPECT_EQ(changed.value("priority", 0), 50);
  EXPECT_EQ(changed.value("changed", false), true);
  // The change comes back as a task event into the adapter's view.
  json task;
  auto end = Clk::now() + 10s;
  while (Clk::now() < end) {
    task = getTask("job-b").value("task", json::object());
    if (task.value("priority", 0) == 50) {
      break;
    }
    std::this_thread::sleep_for(50ms);
  }
  EXPECT_EQ(task.value("priority", 0), 50) << "the change event never reached the view";
  EXPECT_EQ(task.value("deadline", std::string()), "2100-01-01T00:00:00Z");

  manager_->kill(SIGKILL);
  manager_->wait(5s);
  startManager();
  waitHealthy();
  r = http_->Patch("/v1/tasks/job-b", R"({"priority": 50})", "application/json");
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 200) << r->body;
  EXPECT_EQ(json::parse(r->body, nullptr, false).value("changed", true), false)
      << "the restarted manager lost the change";

  transport::Participant p;
  FakeRobots robots(p, 1);
  std::string first;
  end = Clk::now() + 15s;
  while (Clk::now() < end && first.empty()) {
    robots.publishStates();
    for (const auto& a : robots.orders.take()) {
      if (!a.task_id.empty() && first.empty()) {
        first = a.task_id;
      }
    }
    std::this_thread::sleep_for(50ms);
  }
  EXPECT_EQ(first, "job-b") << "priority 50 goes before priority 5";
  r = http_->Patch("/v1/tasks/job-b", R"({"priority": 1})", "application/json");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 409) << r->body;
  const json refused = json::parse(r->body, nullptr, false);
  EXPECT_EQ(refused.value("state", std::string()), "assigned");
}

// The Task topic was keyed by task id with history 1, so of two requests on one task at
// once (the same POST twice, pause and resume together) the second could replace the first before
// The manager took it, and the first was never answered (503 after the ack timeout, ~1 in 20).
// Requests are keyed by request id now. Every one of these concurrent requests must be answered.
TEST_F(FleetE2E, ConcurrentRequestsOnOneTaskAreAllAnswered) {
  constexpr int kTasks = 40;
  std::atomic<int> unanswered{0};
  std::atomic<int> wrong{0};
  auto twice = [&](const std::function<int(httplib::Client&)>& call, std::initializer_list<int> ok) {
    std::vector<std::thread> both;
    for (int k = 0; k < 2; ++k) {
      both.emplace_back([&] {
        httplib::Client c("127.0.0.1", port_);
        c.set_read_timeout(15, 0);
        const int status = call(c);
        if (status == 503 || status < 0) {
          ++unanswered;
        } else if (std::find(ok.begin(), ok.end(), status) == ok.end()) {
          ++wrong;
        }
      });
    }
    for (auto& t : both) {
      t.join();
    }
  };
  for (int i = 0; i < kTasks; ++i) {
    const std::string id = "same-" + std::to_string(i);
    const std::string body = json{{"id", id}, {"kind", "goto"}, {"station", "D-1"}}.dump();
    twice(
        [&](httplib::Client& c) {
          auto r = c.Post("/v1/tasks", body, "application/json");
          return r ? r->status : -1;
        },
        {200, 201});
    std::atomic<int> which{0};
    twice(
        [&](httplib::Client& c) {
          const bool pause = which++ == 0;
          auto r = c.Post("/v1/tasks/" + id + (pause ? "/pause" : "/resume"), "", "application/json");
          return r ? r->status : -1;
        },
        {200});
  }
  EXPECT_EQ(unanswered.load(), 0) << "of " << 4 * kTasks << " requests";
  EXPECT_EQ(wrong.load(), 0);
  for (int i = 0; i < kTasks; ++i) {
    EXPECT_FALSE(getTask("same-" + std::to_string(i)).empty()) << i;
  }
}

// After a manager restart and then an adapter restart, the adapter found none of
// The stored tasks that had not moved since (404). The restarted manager announces every open
// task, and the adapter asks the manager for any task its view lacks (finished ones too).
TEST_F(FleetE2E, AdapterRestartedAfterAManagerRestartFindsEveryStoredTask) {
  std::vector<std::string> ids;
  json batch = json::array();
  for (int i = 0; i < 30; ++i) {
    ids.push_back("kept-" + std::to_string(i));
    batch.push_back({{"id", ids.back()}, {"kind", "goto"}, {"station", "D-1"}});
  }
  auto r = http_->Post("/v1/tasks", batch.dump(), "application/json");
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 201) << r->body;
  r = http_->Delete("/v1/tasks/kept-0");  // finished: stored, but no longer open
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 200) << r->body;

  manager_->kill(SIGKILL);
  manager_.reset();
  startManager();
  waitHealthy();
  adapter_.reset();  // SIGTERM, then the new one on the same port
  startAdapter();
  waitHealthy();

  for (const auto& id : ids) {
    const auto t = getTask(id);
    ASSERT_FALSE(t.empty()) << id << " is stored but the restarted adapter answers 404";
    EXPECT_EQ(t.value("state", ""), id == "kept-0" ? "cancelled" : "queued") << id;
  }
  // The list (the adapter's view) holds every open task, learnt from the manager's announcement.
  const auto deadline = Clk::now() + 10s;
  std::size_t listed = 0;
  while (Clk::now() < deadline) {
    auto l = http_->Get("/v1/tasks?state=queued");
    listed = l && l->status == 200 ? json::parse(l->body)["count"].get<std::size_t>() : 0;
    if (listed == ids.size() - 1) {
      break;
    }
    std::this_thread::sleep_for(100ms);
  }
  EXPECT_EQ(listed, ids.size() - 1);
}

// A roadmap closure over a station, made over HTTP: the adapter sends it (TrafficClosure), the
// manager (on the site's roadmap) holds the waiting task to that station with the reason, and
// assigns it once the closure is reopened.
TEST_F(FleetE2E, AClosureOverHttpHoldsTheTaskToItsStationUntilReopened) {
  // This test's fleet on the small warehouse's site (the manager needs its roadmap).
  adapter_.reset();
  manager_.reset();
  const std::string site = FLEET_SOURCE_DIR "/sim/scenarios/small_warehouse.site.json";
  std::ofstream(dir_ / "manager.json") << json{
      {"db", (dir_ / "site.db").string()},
      {"stations", site},
      {"tick_s", 0.05},
      {"lease_s", 2.0},
      {"sync", "normal"}}.dump();
  std::ofstream(dir_ / "stations.json") << std::ifstream(site).rdbuf();
  startManager();
  startAdapter();
  waitHealthy();
  auto r =
      http_->Put("/v1/traffic/closures/spill",
                 R"({"area": [[27.9, 3.3], [29.3, 3.3], [29.3, 4.7], [27.9, 4.7]], "reason": "wet floor"})",
                 "application/json");
  ASSERT_TRUE(r);
  ASSERT_LT(r->status, 300) << r->body;
  std::this_thread::sleep_for(500ms);  // the manager has the closure before the task
  r = http_->Post("/v1/tasks", R"({"id": "to-d1", "kind": "transport", "pickup": "P-1", "dropoff": "D-1"})",
                  "application/json");
  ASSERT_EQ(r->status, 201) << r->body;
  transport::Participant p;
  FakeRobots robots(p, 2);
  robots.origin = {3.0, 0.9};  // on PARK-1 and PARK-2
  auto waitFor = [&](const std::function<bool(const json&)>& ok, std::chrono::seconds within) {
    const auto end = Clk::now() + within;
    json t;
    while (Clk::now() < end) {
      robots.publishStates();
      robots.work();
      t = getTask("to-d1");
      if (ok(t)) {
        break;
      }
      std::this_thread::sleep_for(50ms);
    }
    return t;
  };
  auto t =
      waitFor([](const json& j) { return j.value("reason", "").find("closed") != std::string::npos; }, 10s);
  EXPECT_EQ(t.value("reason", ""), "station D-1 closed: closure 'spill': wet floor") << t.dump();
  EXPECT_EQ(t.value("state", ""), "queued");
  EXPECT_FALSE(t.contains("eta_ns")) << "no estimate while held";
  std::this_thread::sleep_for(1s);
  EXPECT_EQ(getTask("to-d1").value("state", ""), "queued") << "robots are free, but the station is closed";

  r = http_->Delete("/v1/traffic/closures/spill");
  ASSERT_TRUE(r);
  ASSERT_LT(r->status, 300) << r->body;
  t = waitFor([](const json& j) { return j.value("state", "") == "done"; }, 20s);
  EXPECT_EQ(t.value("state", ""), "done") << t.dump();
}
