// The HTTP API against a fake gateway (no DDS): every documented status code and error body.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <thread>

#include "api_fixture.hpp"
#include "event_stream_reader.hpp"

using namespace fleet;
using namespace fleet::wms;
using nlohmann::json;
using namespace fleet::wms::testing;
using ::testing::HasSubstr;

namespace {
const std::string kTask = R"({"id": "t-1", "kind": "transport", "pickup": "P-1", "dropoff": "D-1"})";
}  // namespace

TEST_F(Api, CreateThenIdempotentRepeatThenConflict) {
  start();
  auto r = post(kTask);
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 201);
  EXPECT_EQ(json::parse(r->body)["state"], "queued");
  r = post(kTask);
  EXPECT_EQ(r->status, 200);
  EXPECT_EQ(json::parse(r->body)["result"], "duplicate");
  r = post(R"({"id": "t-1", "kind": "transport", "pickup": "P-1", "dropoff": "D-1", "priority": 5})");
  EXPECT_EQ(r->status, 409);
  EXPECT_EQ(json::parse(r->body)["error"], "conflict");
  r = client_->Get("/v1/tasks/t-1");
  ASSERT_EQ(r->status, 200);
  EXPECT_EQ(json::parse(r->body)["task"]["pickup"], "P-1");
}

TEST_F(Api, ValidationErrorsNameTheField) {
  start();
  auto r =
      post(R"({"id": "t-2", "kind": "transport", "pickup": "P-404", "dropoff": "D-1", "priority": 99999})");
  ASSERT_EQ(r->status, 400);
  const auto body = json::parse(r->body);
  EXPECT_EQ(body["error"], "invalid");
  std::string paths;
  for (const auto& f : body["fields"]) {
    paths += f["path"].get<std::string>() + ";";
  }
  EXPECT_THAT(paths, HasSubstr("priority;"));
  r = post(R"({"id": "t-2", "kind": "transport", "pickup": "P-404", "dropoff": "D-1"})");
  ASSERT_EQ(r->status, 400);
  EXPECT_EQ(json::parse(r->body)["fields"][0]["path"], "pickup");
  EXPECT_THAT(r->body, HasSubstr("P-404"));
  r = post("{\"id\": ");
  EXPECT_EQ(r->status, 400);
  EXPECT_EQ(json::parse(r->body)["error"], "invalid_json");
  r = post(R"([{"id": "a", "kind": "goto", "station": "D-1"}, {"id": "b", "kind": "fly"}])");
  ASSERT_EQ(r->status, 400);
  EXPECT_THAT(r->body, HasSubstr("[1].kind"));
  EXPECT_TRUE(gateway_.bodies.empty()) << "an invalid batch stores nothing";
}

TEST_F(Api, BatchReportsEachItem) {
  start();
  ASSERT_EQ(post(kTask)->status, 201);
  auto r = post(R"({"tasks": [{"id": "t-1", "kind": "transport", "pickup": "P-1", "dropoff": "D-1"},
                              {"id": "t-9", "kind": "goto", "station": "D-1"}]})");
  ASSERT_EQ(r->status, 200);
  const auto res = json::parse(r->body)["results"];
  EXPECT_EQ(res[0]["status"], 200);
  EXPECT_EQ(res[1]["status"], 201);
}

TEST_F(Api, NotFoundTooLargeUnknownStateAndCancel) {
  ApiSettings s;
  s.limits.maxBodyBytes = 2048;
  s.maxBatch = 2;
  start(s);
  EXPECT_EQ(client_->Get("/v1/tasks/nope")->status, 404);
  EXPECT_EQ(client_->Delete("/v1/tasks/nope")->status, 404);
  EXPECT_EQ(post(std::string(4096, ' ') + kTask)->status, 413);
  auto r =
      post(R"([{"id": "a", "kind": "goto", "station": "D-1"}, {"id": "b", "kind": "goto", "station": "D-1"},
                    {"id": "c", "kind": "goto", "station": "D-1"}])");
  EXPECT_EQ(r->status, 413);
  r = client_->Get("/v1/tasks?state=flying");
  EXPECT_EQ(r->status, 400);
  EXPECT_THAT(r->body, HasSubstr("unknown task state"));
  ASSERT_EQ(post(kTask)->status, 201);
  EXPECT_EQ(client_->Delete("/v1/tasks/t-1")->status, 200);
}

TEST_F(Api, ManagerUnreachableGives503AndNothingIsClaimed) {
  start();
  gateway_.online = false;
  auto r = post(kTask);
  EXPECT_EQ(r->status, 503);
  EXPECT_EQ(r->get_header_value("Retry-After"), "2");
  EXPECT_EQ(client_->Get("/v1/health")->status, 503);
  gateway_.online = true;
  gateway_.silent = true;  // matched but never answers
  r = post(kTask);
  EXPECT_EQ(r->status, 503);
  EXPECT_EQ(client_->Get("/v1/tasks/t-1")->status, 404) << "an unacknowledged task is not shown as accepted";
}

TEST_F(Api, TooManyRequestsInFlightGet429) {
  ApiSettings s;
  s.limits.maxInFlight = 1;
  start(s);
  gateway_.delay = std::chrono::milliseconds(500);
  int slowStatus = 0;
  std::thread slow([&] {
    httplib::Client c("127.0.0.1", api_->port());
    slowStatus = c.Post("/v1/tasks", kTask, "application/json")->status;
  });
  std::this_thread::sleep_for(std::chrono::milliseconds(150));
  auto r = post(R"({"id": "t-2", "kind": "goto", "station": "D-1"})");
  EXPECT_EQ(r->status, 429);
  EXPECT_EQ(r->get_header_value("Retry-After"), "1");
  slow.join();
  EXPECT_EQ(slowStatus, 201);
  EXPECT_EQ(gateway_.bodies.count("t-2"), 0u) << "a refused request stores nothing";
}

TEST_F(Api, BearerTokenIsRequiredWhenConfigured) {
  ApiSettings s;
  s.token = "s3cret";
  start(s);
  // Health is for probes, which carry no token, and tells nothing secret: never 401.
  auto h = client_->Get("/v1/health");
  EXPECT_EQ(h->status, 200);
  EXPECT_EQ(h->body.find("s3cret"), std::string::npos);
  EXPECT_EQ(client_->Get("/v1/metrics")->status, 401);
  EXPECT_EQ(post(kTask)->status, 401);
  EXPECT_EQ(post(kTask, {{"Authorization", "Bearer wrong"}})->status, 401);
  EXPECT_TRUE(gateway_.bodies.empty());
  EXPECT_EQ(post(kTask, {{"Authorization", "Bearer s3cret"}})->status, 201);
  EXPECT_EQ(client_->Get("/v1/health", {{"Authorization", "Bearer s3cret"}})->status, 200);
}

TEST_F(Api, NoTokenMeansOpenAndListensOnLoopback) {
  start();
  EXPECT_EQ(client_->Get("/v1/health")->status, 200);
  auto cfg = Config::fromText("{}", "t");
  unsetenv("FLEET_WMS_TOKEN");
  const auto s = readApiSettings(cfg);
  EXPECT_EQ(s.host, "127.0.0.1");
  EXPECT_TRUE(s.token.empty());
}

TEST_F(Api, EventsStreamAndMetrics) {
  start();
  EventStreamReader reader(api_->port(), "\"state\":\"done\"");
  ASSERT_TRUE(reader.waitOpen()) << "GET /v1/events did not answer 200 with an open stream";
  view_.onEvent({"t-5", msg::TaskState::Assigned, "r1", "", 1, 1, ""});
  view_.onEvent({"t-5", msg::TaskState::Done, "r1", "", 2, 2, ""});
  ASSERT_TRUE(reader.finish()) << "the stream did not bring the done event; it brought:\n"
                               << reader.received();
  const auto& received = reader.received();
  EXPECT_THAT(received, HasSubstr("event: task"));
  EXPECT_THAT(received, HasSubstr("\"state\":\"assigned\""));
  auto m = json::parse(client_->Get("/v1/metrics")->body);
  EXPECT_EQ(m["tasks_by_state"]["done"], 1);
}

TEST_F(Api, PauseAndResumeReachTheManagerAndAnswerWithTheState) {
  start();
  ASSERT_EQ(post(kTask)->status, 201);
  auto r = client_->Post("/v1/tasks/t-1/pause", "", "application/json");
  ASSERT_EQ(r->status, 200) << r->body;
  EXPECT_EQ(json::parse(r->body), json::parse(R"({"id": "t-1", "paused": true, "state": "en_route"})"));
  r = client_->Post("/v1/tasks/t-1/resume", "", "application/json");
  ASSERT_EQ(r->status, 200) << r->body;
  EXPECT_EQ(json::parse(r->body)["paused"], false);
  EXPECT_EQ(gateway_.controls,
            (std::vector<msg::TaskControl>{msg::TaskControl::Pause, msg::TaskControl::Resume}));
  EXPECT_EQ(client_->Post("/v1/tasks/nope/pause", "", "application/json")->status, 404);
  EXPECT_EQ(client_->Post("/v1/tasks/a%20b/pause", "", "application/json")->status, 400);
  gateway_.online = false;
  r = client_->Post("/v1/tasks/t-1/pause", "", "application/json");
  EXPECT_EQ(r->status, 503);
  EXPECT_THAT(r->body, HasSubstr("nothing was paused"));
}

// A TaskEvent reason that is not UTF-8 (from a robot's TaskStatus.error) made the adapter
// exit while an event stream was open and made GET /v1/tasks answer 500 for good. Text that gets
// past the edge unrepaired is now written with U+FFFD; the stream and the list keep working.
TEST_F(Api, TextThatIsNotUtf8NeitherStopsTheStreamNorBreaksTheList) {
  start();
  EventStreamReader reader(api_->port(), "\"state\":\"done\"");
  ASSERT_TRUE(reader.waitOpen()) << "GET /v1/events did not answer 200 with an open stream";
  view_.onEvent({"t-7", msg::TaskState::Failed, "r1", "motor \xFF\xFE fault", 1, 1, ""});
  view_.onEvent({"t-8", msg::TaskState::Done, "r1", "", 2, 1, ""});
  ASSERT_TRUE(reader.finish()) << "the stream did not bring the done event; it brought:\n"
                               << reader.received();
  EXPECT_THAT(reader.received(), HasSubstr("motor \xEF\xBF\xBD\xEF\xBF\xBD fault"));
  auto r = client_->Get("/v1/tasks");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 200) << r->body;
  EXPECT_EQ(json::parse(r->body)["count"], 2);
  r = client_->Get("/v1/tasks/t-7");
  ASSERT_EQ(r->status, 200);
  EXPECT_EQ(json::parse(r->body)["reason"], "motor \xEF\xBF\xBD\xEF\xBF\xBD fault");
}

// A task the view does not hold (an adapter started after its events) is asked of
// The manager before answering 404.
TEST_F(Api, TaskMissingFromTheViewIsAskedOfTheManager) {
  start();
  ASSERT_EQ(post(kTask)->status, 201);
  FleetView fresh;  // a restarted adapter's empty view, same manager
  ApiSettings settings;
  settings.port = 0;
  settings.ackTimeoutMs = 200;
  HttpApi second(settings, stations_, gateway_, fresh, clock_);
  ASSERT_TRUE(second.bind());
  std::thread serving([&] { second.serve(); });
  httplib::Client c("127.0.0.1", second.port());
  auto r = c.Get("/v1/tasks/t-1");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 200) << r->body;
  EXPECT_EQ(json::parse(r->body)["id"], "t-1");
  EXPECT_EQ(gateway_.controls.back(), msg::TaskControl::Query);
  EXPECT_TRUE(fresh.task("t-1")) << "kept in the view";
  EXPECT_EQ(c.Get("/v1/tasks/t-404")->status, 404);
  second.stop();
  serving.join();
}

// A park or charge task may leave its station out: the manager chooses one when it assigns the
// task. On a site without such a station that could never happen, so the task is refused at once.
TEST_F(Api, AStationlessParkTaskIsRefusedOnASiteWithoutParking) {
  start();
  auto r = post(R"({"id": "park-1", "kind": "park"})");
  ASSERT_EQ(r->status, 400);
  const auto body = json::parse(r->body);
  EXPECT_EQ(body["fields"][0]["path"], "station");
  EXPECT_EQ(body["fields"][0]["reason"], "no parking station on this site to choose from");
  EXPECT_TRUE(gateway_.bodies.empty());
}

// The station the manager chose arrives with the task's events; GET shows it until the task goes
// back to the queue (where the next robot gets its own choice).
TEST_F(Api, TheStationTheManagerChoseIsShownWithTheTask) {
  start();
  view_.onAccepted("park-2", R"({"id": "park-2", "kind": "park"})", msg::TaskState::Queued, 1);
  view_.onEvent({"park-2", msg::TaskState::Assigned, "r1",
                 "allocated to the nearest free parking station K-2", 2, 2, "K-2"});
  auto r = client_->Get("/v1/tasks/park-2");
  ASSERT_EQ(r->status, 200);
  auto body = json::parse(r->body);
  EXPECT_EQ(body["task"]["station"], "K-2");
  EXPECT_EQ(body["station"], "K-2");
  EXPECT_EQ(body["station_chosen"], true);
  view_.onEvent({"park-2", msg::TaskState::Requeued, "", "robot r1 lost", 3, 3, ""});
  body = json::parse(client_->Get("/v1/tasks/park-2")->body);
  EXPECT_FALSE(body.contains("station"));
  EXPECT_FALSE(body["task"].contains("station"));
}

TEST_F(Api, RoadmapClosuresAreSentListedAndReopened) {
  start();
  // Node ids are checked against the roadmap once the adapter has one.
  msg::Roadmap rm;
  rm.epoch = 3;
  for (int i = 0; i < 10; ++i) {
    rm.nodes.push_back({i, static_cast<double>(i), 0.0});
    rm.kinds.push_back(0);
    rm.open.push_back(true);
  }
  view_.onRoadmap(rm);
  const std::string good = R"({"area": [[1, 1], [3, 1], [3, 2]], "nodes": [4], "lanes": [[5, 6], [6, 5]],
                               "reason": "spill in aisle 3"})";
  auto r = client_->Put("/v1/traffic/closures/spill-3", good, "application/json");
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 202) << r->body;
  auto j = json::parse(r->body);
  EXPECT_EQ(j["id"], "spill-3");
  EXPECT_EQ(j["nodes"], json::array({4}));
  EXPECT_EQ(j["lanes"], json::parse("[[5, 6], [6, 5]]"));
  ASSERT_EQ(gateway_.closuresSent.size(), 1U);
  const auto sent = gateway_.closuresSent[0];
  EXPECT_TRUE(sent.active);
  EXPECT_EQ(sent.area.size(), 3U);
  EXPECT_EQ(sent.reason, "spill in aisle 3");
  view_.onClosure(sent);  // as the DDS gateway does
  r = client_->Get("/v1/traffic/closures");
  ASSERT_TRUE(r);
  j = json::parse(r->body);
  EXPECT_EQ(j["count"], 1);
  EXPECT_EQ(j["closures"][0]["id"], "spill-3");
  EXPECT_EQ(j["roadmap"]["epoch"], 3);
  // Bad bodies: each wrong field named, nothing sent.
  const std::pair<const char*, const char*> bad[] = {
      {R"({"nodes": [10]})", "nodes[0]"},
      {R"({"nodes": [-1]})", "nodes[0]"},
      {R"({"area": [[0, 0], [1, 1]]})", "area"},
      {R"({"area": [[0, 0], [1, "x"], [1, 1]]})", "area[1]"},
      {R"({"lanes": [[1]]})", "lanes[0]"},
      {R"({"reason": "no target"})", ""},
      {R"({"nodes": [1], "colour": "red"})", "colour"},
      {R"([1, 2])", ""},
  };
  for (const auto& [body, path] : bad) {
    r = client_->Put("/v1/traffic/closures/c2", body, "application/json");
    ASSERT_TRUE(r);
    EXPECT_EQ(r->status, 400) << body;
    const auto e = json::parse(r->body);
    bool named = false;
    for (const auto& f : e["fields"]) {
      named = named || f["path"] == path;
    }
    EXPECT_TRUE(named) << body << " -> " << r->body;
  }
  r = client_->Put("/v1/traffic/closures/bad%20id", good, "application/json");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 400);
  EXPECT_EQ(gateway_.closuresSent.size(), 1U) << "nothing sent for a bad request";
  // The transport refusing: 503, said.
  gateway_.closureProblem = "no permission";
  r = client_->Put("/v1/traffic/closures/c3", good, "application/json");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 503);
  EXPECT_NE(r->body.find("no permission"), std::string::npos);
  gateway_.closureProblem.clear();
  // Reopened: sent inactive, known or not.
  r = client_->Delete("/v1/traffic/closures/spill-3");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 202);
  EXPECT_EQ(json::parse(r->body)["known"], true);
  ASSERT_EQ(gateway_.closuresSent.size(), 2U);
  EXPECT_FALSE(gateway_.closuresSent[1].active);
  view_.onClosure(gateway_.closuresSent[1]);
  r = client_->Delete("/v1/traffic/closures/made-elsewhere");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 202);
  EXPECT_EQ(json::parse(r->body)["known"], false);
  r = client_->Get("/v1/traffic/closures");
  EXPECT_EQ(json::parse(r->body)["count"], 0);
}
