// The dashboard's side of the WMS adapter against a fake manager (no DDS): the page without login,
// browser sessions (cookie flags, CSRF, token never accepted in a URL, other tokens and expired
// sessions refused), the robot API (snapshot, hold/release, home, charge, bad ids), the stream and
// its traffic layer (roadmap, releases, station queues), and the scopes the page is told.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <thread>

#include "api_fixture.hpp"
#include "browser_session.hpp"
#include "event_stream_reader.hpp"
#include "http_api.hpp"
#include "traffic_layer.hpp"

using namespace fleet;
using namespace fleet::wms;
using fleet::wms::testing::EventStreamReader;
using fleet::wms::testing::RawClient;
using nlohmann::json;
using ::testing::HasSubstr;
namespace fs = std::filesystem;

namespace {

/// Acknowledges everything as stored and remembers the requests; knows robots r1 and r2.
class RecordingGateway : public TaskGateway {
 public:
  std::vector<std::optional<msg::TaskAck>> submit(const std::vector<msg::Task>& requests,
                                                  std::chrono::milliseconds) override {
    std::vector<std::optional<msg::TaskAck>> out;
    for (const auto& r : requests) {
      seen.push_back(r);
      msg::TaskAck a{r.request_id, r.task_id, msg::AckResult::Stored, msg::TaskState::Queued, "", 0};
      const bool robotControl =
          r.control == msg::TaskControl::HoldRobot || r.control == msg::TaskControl::ReleaseRobot;
      if (robotControl && r.robot != "r1" && r.robot != "r2") {
        a.result = msg::AckResult::NotFound;
      }
      out.emplace_back(a);
    }
    return out;
  }
  [[nodiscard]] bool managerOnline() const override { return true; }
  std::vector<msg::Task> seen;
};

msg::RobotState robot(const std::string& id, double x, double y, std::int64_t stamp) {
  msg::RobotState r;
  r.robot_id = id;
  r.pose = {x, y, 0.5};
  r.stamp_ns = stamp;
  r.mode = msg::RobotMode::Moving;
  r.battery = 0.8f;
  r.radius = 0.3f;
  return r;
}

/// A station P-1 at (5, 1) on a lane 0-1-2 (y = 5): dock 3, approach 4 above it, a queue of two
/// (5 head, 6 tail) above that, entered at the tail from lane node 1 and left sideways to node 2.
msg::Roadmap smallRoadmap(std::uint32_t epoch = 7) {
  msg::Roadmap m;
  m.epoch = epoch;
  m.nodes = {{0, 3.0, 5.0}, {1, 4.0, 5.0}, {2, 6.0, 5.0},  {3, 5.0, 1.0},
             {4, 5.0, 2.0}, {5, 5.0, 3.0}, {6, 5.004, 4.0}};
  m.kinds = {0, 0, 0, 1, 2, 3, 3};
  m.open = {true, true, true, true, true, true, true};
  auto both = [&](std::int32_t a, std::int32_t b) {
    m.edges.push_back({a, b, 1.0F, true});
    m.edges.push_back({b, a, 1.0F, true});
  };
  both(0, 1);
  both(1, 2);
  both(2, 4);
  both(3, 4);
  m.edges.push_back({5, 4, 1.0F, true});   // the head drives on to the approach
  m.edges.push_back({6, 5, 1.0F, true});   // the tail to the head
  m.edges.push_back({5, 2, 1.0F, true});   // left sideways
  m.edges.push_back({1, 6, 1.0F, true});   // joined at the tail
  m.edges.push_back({0, 2, 2.0F, false});  // a closed lane
  return m;
}

msg::TrafficRelease release(const std::string& robot, std::uint32_t epoch, std::uint32_t seq,
                            std::vector<std::int32_t> base, std::vector<std::int32_t> horizon) {
  const auto m = smallRoadmap();
  msg::TrafficRelease r;
  r.robot_id = robot;
  r.epoch = epoch;
  r.seq = seq;
  for (const auto v : base) {
    r.base.push_back(m.nodes[static_cast<std::size_t>(v)]);
  }
  for (const auto v : horizon) {
    r.horizon.push_back(m.nodes[static_cast<std::size_t>(v)]);
  }
  return r;
}

/// The data of every `event: name` in an SSE text, in order; one not complete yet (a stream read
/// so far) is left out.
std::vector<json> eventsNamed(const std::string& text, const std::string& name) {
  std::vector<json> out;
  const std::string head = "event: " + name + "\ndata: ";
  for (auto at = text.find(head); at != std::string::npos; at = text.find(head, at + 1)) {
    const auto start = at + head.size();
    const auto end = text.find("\n\n", start);
    if (end == std::string::npos) {
      break;
    }
    out.push_back(json::parse(text.substr(start, end - start)));
  }
  return out;
}

/// The dashboard's stream makes its snapshot when the server first polls it, after the response
/// head: a test changes the fleet only once the snapshot has arrived, or the change is in the
/// snapshot and never sent as one.
::testing::AssertionResult snapshotArrived(EventStreamReader& stream) {
  if (stream.waitFor("event: snapshot")) {
    return ::testing::AssertionSuccess();
  }
  return ::testing::AssertionFailure() << "GET /v1/stream sent no snapshot; it sent:\n" << stream.received();
}

class Dash : public ::testing::Test {
 protected:
  void start(const std::string& token) {
    ApiSettings s;
    s.token = token;
    start(s);
  }
  void start(ApiSettings s) {
    s.port = 0;
    s.ackTimeoutMs = 200;
    api_ = std::make_unique<HttpApi>(s, stations_, gateway_, view_, clock_);
    api_->dashboard().setSite(
        json{{"name", "test"}, {"stations", json::array()}, {"homes", {{"r1", "PARK-1"}}}});
    spec_.watch(*api_);
    ASSERT_TRUE(api_->bind());
    thread_ = std::thread([this] { api_->serve(); });
    client_ = std::make_unique<httplib::Client>("127.0.0.1", api_->port());
    view_.onRobot(robot("r1", 1.0, 1.0, 1));
    view_.onRobot(robot("r2", 9.0, 1.0, 1));
  }
  void TearDown() override {
    if (api_) {
      api_->stop();
      thread_.join();
    }
    spec_.report();
  }
  /// POST /v1/session with the token: the session cookie ("fleet_session=...") and the CSRF token.
  std::pair<std::string, std::string> login(const std::string& token) {
    auto r = client_->Post("/v1/session", {{"Authorization", "Bearer " + token}}, "", "text/plain");
    EXPECT_TRUE(r && r->status == 201);
    const std::string setCookie = r->get_header_value("Set-Cookie");
    return {setCookie.substr(0, setCookie.find(';')), json::parse(r->body)["csrf"].get<std::string>()};
  }
  StationMap stations_ = *StationMap::fromJson(json::parse(R"({"stations": [
    {"name": "P-1", "x": 1, "y": 1, "kinds": ["pickup"]},
    {"name": "D-1", "x": 5, "y": 1, "kinds": ["dropoff"]},
    {"name": "PARK-1", "x": 0, "y": 3, "kinds": ["parking"]},
    {"name": "PARK-2", "x": 9, "y": 3, "kinds": ["parking"]},
    {"name": "CHG-1", "x": 0, "y": 0, "kinds": ["charging"]},
    {"name": "CHG-2", "x": 10, "y": 0, "kinds": ["charging"]}]})"));
  RecordingGateway gateway_;
  FleetView view_;
  WallClock clock_;
  std::unique_ptr<HttpApi> api_;
  std::thread thread_;
  std::unique_ptr<httplib::Client> client_;
  fleet::wms::testing::SpecWatch spec_;
};

}  // namespace

TEST_F(Dash, ThePageNeedsNoLoginButTheDataDoes) {
  start("s3cret");
  auto page = client_->Get("/dashboard/");
  ASSERT_TRUE(page);
  EXPECT_EQ(page->status, 200);
  EXPECT_THAT(page->get_header_value("Content-Type"), HasSubstr("text/html"));
  EXPECT_THAT(page->body, HasSubstr("dashboard.js"));
  auto js = client_->Get("/dashboard/map_view.js");
  ASSERT_TRUE(js);
  EXPECT_THAT(js->get_header_value("Content-Type"), HasSubstr("javascript"));
  EXPECT_EQ(client_->Get("/dashboard/nope.js")->status, 404);
  auto root = client_->Get("/");
  ASSERT_TRUE(root);
  EXPECT_EQ(root->status, 302);
  EXPECT_EQ(root->get_header_value("Location"), "dashboard/");  // relative: kept under a path prefix
  EXPECT_EQ(client_->Get("/v1/robots")->status, 401);
  EXPECT_EQ(client_->Get("/v1/stream")->status, 401);
  EXPECT_EQ(client_->Get("/v1/session")->status, 401) << "the page shows its login prompt on this";
  EXPECT_EQ(client_->Get("/v1/robots?token=s3cret")->status, 400) << "a token in a URL is never accepted";
}

TEST_F(Dash, ASessionCookieReadsAndActsOnlyWithItsCsrfToken) {
  start("s3cret");
  auto wrong = client_->Post("/v1/session", {{"Authorization", "Bearer nope"}}, "", "text/plain");
  ASSERT_TRUE(wrong);
  EXPECT_EQ(wrong->status, 401);
  EXPECT_TRUE(wrong->get_header_value("Set-Cookie").empty());
  auto r = client_->Post("/v1/session", {{"Authorization", "Bearer s3cret"}}, "", "text/plain");
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 201);
  const std::string setCookie = r->get_header_value("Set-Cookie");
  EXPECT_THAT(setCookie, HasSubstr("HttpOnly"));
  EXPECT_THAT(setCookie, HasSubstr("SameSite=Strict"));
  EXPECT_THAT(setCookie, ::testing::Not(HasSubstr("s3cret")));
  const auto [cookie, csrf] = login("s3cret");
  ASSERT_FALSE(csrf.empty());

  auto robots = client_->Get("/v1/robots", {{"Cookie", cookie}});
  ASSERT_TRUE(robots);
  EXPECT_EQ(robots->status, 200);
  EXPECT_EQ(json::parse(robots->body)["count"], 2);
  auto session = client_->Get("/v1/session", {{"Cookie", cookie}});
  EXPECT_EQ(json::parse(session->body)["csrf"], csrf) << "a reloaded page gets its CSRF token back";

  auto noCsrf = client_->Post("/v1/robots/r1/pause", {{"Cookie", cookie}}, "", "text/plain");
  ASSERT_TRUE(noCsrf);
  EXPECT_EQ(noCsrf->status, 403);
  auto badCsrf =
      client_->Post("/v1/robots/r1/pause", {{"Cookie", cookie}, {kCsrfHeader, csrf + "0"}}, "", "text/plain");
  EXPECT_EQ(badCsrf->status, 403);
  EXPECT_TRUE(gateway_.seen.empty()) << "a refused request reached the manager";
  auto ok = client_->Post("/v1/robots/r1/pause", {{"Cookie", cookie}, {kCsrfHeader, csrf}}, "", "text/plain");
  ASSERT_TRUE(ok);
  EXPECT_EQ(ok->status, 200) << ok->body;

  std::string tampered = cookie;
  tampered.back() = tampered.back() == '0' ? '1' : '0';
  auto forged = client_->Get("/v1/robots", {{"Cookie", tampered}});
  EXPECT_EQ(forged->status, 401) << "a tampered cookie";
}

TEST(BrowserSessions, ExpireAndEndWhenTheTokenChanges) {
  const auto tokenA = TokenStore::single("token", "token-a");
  BrowserSessions s(tokenA, false, 60);
  const std::string c = *s.issue("token", 1000);
  EXPECT_TRUE(s.check(c, 1059));
  EXPECT_FALSE(s.check(c, 1061)) << "expired";
  const auto tokenB = TokenStore::single("token", "token-b");
  EXPECT_FALSE(BrowserSessions(tokenB, false, 60).check(c, 1000)) << "made from another token";
  const auto tokenA2 = TokenStore::single("token", "token-a");
  EXPECT_FALSE(BrowserSessions(tokenA2, false, 60).check(c, 1000))
      << "sessions live in the adapter's table: a restart ends them";
  const auto renamed = TokenStore::single("other", "token-a");
  EXPECT_FALSE(BrowserSessions(renamed, false, 60).check(c, 1000)) << "the name is part of the session";
  EXPECT_FALSE(s.issue("nobody", 1000)) << "no token has that name";
  EXPECT_FALSE(s.check("garbage", 1000));
  EXPECT_FALSE(s.check("", 1000));
  EXPECT_NE(*s.issue("token", 1000), c) << "each session has its own nonce";
  EXPECT_EQ(cookieValue("a=1; fleet_session=xyz; b=2", kSessionCookie), "xyz");
  EXPECT_EQ(cookieValue("a=1", kSessionCookie), "");
  EXPECT_THAT(s.setCookie(c), ::testing::Not(HasSubstr("Secure")));
  EXPECT_THAT(BrowserSessions(tokenA, true, 60).setCookie(c), HasSubstr("; Secure"))
      << "served over https, the cookie is never sent over plain http";
}

TEST_F(Dash, PauseAndResumeHoldTheRobotThroughTheManager) {
  start("");
  auto p = client_->Post("/v1/robots/r1/pause", "", "text/plain");
  ASSERT_TRUE(p);
  EXPECT_EQ(p->status, 200);
  EXPECT_EQ(json::parse(p->body)["paused"], true);
  auto q = client_->Post("/v1/robots/r1/resume", "", "text/plain");
  EXPECT_EQ(q->status, 200);
  ASSERT_EQ(gateway_.seen.size(), 2u);
  EXPECT_EQ(gateway_.seen[0].control, msg::TaskControl::HoldRobot);
  EXPECT_EQ(gateway_.seen[0].robot, "r1");
  EXPECT_EQ(gateway_.seen[1].control, msg::TaskControl::ReleaseRobot);
  EXPECT_EQ(client_->Post("/v1/robots/r7/pause", "", "text/plain")->status, 404) << "a robot never seen";
  auto odd = client_->Post("/v1/robots/r%24%3Cb%3E/pause", "", "text/plain");
  EXPECT_EQ(odd->status, 400);
  EXPECT_THAT(odd->body, HasSubstr("robot id"));
  EXPECT_EQ(client_->Post("/v1/robots/r1/dance", "", "text/plain")->status, 404);
}

TEST_F(Dash, HomeGoesToTheRobotsParkingPlaceAndChargeToTheNearestCharger) {
  start("");
  auto home = client_->Post("/v1/robots/r2/home", "", "text/plain");
  ASSERT_TRUE(home);
  EXPECT_EQ(home->status, 201) << home->body;
  EXPECT_EQ(json::parse(home->body)["station"], "PARK-2") << "r2 has no home named: the nearest parking";
  auto home1 = client_->Post("/v1/robots/r1/home", "", "text/plain");
  EXPECT_EQ(json::parse(home1->body)["station"], "PARK-1") << "r1's home from the scenario";
  auto charge = client_->Post("/v1/robots/r2/charge", "", "text/plain");
  EXPECT_EQ(json::parse(charge->body)["station"], "CHG-2");
  ASSERT_EQ(gateway_.seen.size(), 3u);
  EXPECT_EQ(gateway_.seen[0].kind, msg::TaskKind::Park);
  EXPECT_EQ(gateway_.seen[0].robot, "r2");
  EXPECT_EQ(gateway_.seen[2].kind, msg::TaskKind::Charge);
  auto chosen = client_->Post("/v1/robots/r2/charge", R"({"station": "CHG-1"})", "application/json");
  EXPECT_EQ(json::parse(chosen->body)["station"], "CHG-1");
  auto wrongKind = client_->Post("/v1/robots/r2/charge", R"({"station": "P-1"})", "application/json");
  EXPECT_EQ(wrongKind->status, 400) << wrongKind->body;
  auto notJson = client_->Post("/v1/robots/r2/home", "{", "application/json");
  EXPECT_EQ(notJson->status, 400);
}

TEST_F(Dash, TheStreamStartsWithASnapshotThenSendsWhatChanged) {
  start("");
  EventStreamReader stream(api_->port(), "/v1/stream", [](const std::string& got) {
    return got.find("event: robots") != std::string::npos && got.find("event: task") != std::string::npos &&
           got.find("event: risk") != std::string::npos;
  });
  ASSERT_TRUE(snapshotArrived(stream));
  view_.onRobot(robot("r2", 8.0, 2.0, 2));
  view_.onEvent(msg::TaskEvent{"t<1>", msg::TaskState::Assigned, "r2", "", 5, 1, ""});
  msg::RiskMap m;
  m.width = 4;
  m.height = 2;
  m.resolution = 0.5;
  m.levels = 3;
  m.runs = {{0, 5}, {3, 2}, {1, 1}};
  view_.onRisk(m);
  ASSERT_TRUE(stream.finish())
      << "the stream did not bring the robot, the task and the risk map; it brought:\n"
      << stream.received();
  const std::string got = stream.received();
  const auto snap = got.find("event: snapshot\ndata: ");
  const auto snapEnd = got.find("\n\n", snap);
  const json s = json::parse(got.substr(snap + 22, snapEnd - snap - 22));
  EXPECT_EQ(s["robots"].size(), 2u);
  const auto upd = got.find("event: robots\ndata: ");
  ASSERT_NE(upd, std::string::npos);
  const json u = json::parse(got.substr(upd + 20, got.find("\n\n", upd) - upd - 20));
  ASSERT_EQ(u["robots"].size(), 1u) << "only the robot that changed";
  EXPECT_EQ(u["robots"][0]["id"], "r2");
  EXPECT_DOUBLE_EQ(u["robots"][0]["pose"]["x"].get<double>(), 8.0);
  EXPECT_THAT(got, HasSubstr(R"("id":"t<1>")"));
  const auto risk = got.find("event: risk\ndata: ");
  ASSERT_NE(risk, std::string::npos);
  const json rj = json::parse(got.substr(risk + 18, got.find("\n\n", risk) - risk - 18));
  EXPECT_EQ(rj["levels"], 3);
  EXPECT_EQ(rj["runs"], json::array({0, 5, 3, 2, 1, 1})) << "levels and counts, flattened";
}

TEST_F(Dash, StationQueuesAreReadOffTheRoadmapsShapeAndNamedAfterTheSite) {
  const auto m = smallRoadmap();
  const json stations =
      json::parse(R"([{"name": "P-1", "x": 5.0, "y": 1.0}, {"name": "D-1", "x": 9, "y": 9}])");
  const auto queues = stationQueues(m, stations);
  ASSERT_EQ(queues.size(), 1u);
  EXPECT_EQ(queues[0].station, "P-1");
  EXPECT_EQ(queues[0].dock, 3);
  EXPECT_EQ(queues[0].nodes, (std::vector<std::int32_t>{5, 6})) << "head first, then back to the tail";
  EXPECT_EQ(stationQueues(m, json::array())[0].station, "node 3") << "a dock the site does not name";

  const json j = roadmapJson(m, queues);
  EXPECT_EQ(j["epoch"], 7);
  EXPECT_EQ(j["nodes"].size(), 14u);
  EXPECT_EQ(j["nodes"][13], 4.0) << "positions to the centimetre";
  EXPECT_EQ(j["kinds"], json::array({0, 0, 0, 1, 2, 3, 3}));
  EXPECT_EQ(j["lanes"], json::array({0, 1, 1, 2, 2, 4, 3, 4})) << "a lane driven both ways once";
  EXPECT_EQ(j["one_way"], json::array({5, 4, 6, 5, 5, 2, 1, 6}));
  EXPECT_EQ(j["closed_lanes"], json::array({0, 2}));
  EXPECT_EQ(j["queues"][0], json::parse(R"({"station": "P-1", "dock": 3, "nodes": [5, 6]})"));

  // r1 waits at the head, r2 behind it, r3 is at the station; r4 drives by, r5 is elsewhere.
  std::vector<msg::RobotState> robots = {robot("r2", 5.0, 4.1, 1), robot("r1", 5.1, 3.0, 1),
                                         robot("r3", 5.0, 1.05, 1), robot("r4", 5.5, 3.0, 1),
                                         robot("r5", 1.0, 1.0, 1)};
  const json q = queuesJson(queues, m, robots);
  EXPECT_EQ(q, json::parse(R"([{"station": "P-1", "at": "r3", "waiting": ["r1", "r2"], "length": 2}])"));
  EXPECT_EQ(queuesJson(queues, m, {})[0]["waiting"], json::array());

  msg::Roadmap huge;
  huge.nodes.assign(kMaxDrawnNodes + 1, {0, 0.0, 0.0});
  huge.kinds.assign(huge.nodes.size(), 0);
  huge.open.assign(huge.nodes.size(), true);
  EXPECT_TRUE(roadmapJson(huge, {}).is_null()) << "too large to draw";
}

TEST_F(Dash, ReleasesOfAnEarlierTrafficManagerAreDropped) {
  view_.onRelease(release("r1", 5, 3, {0, 1}, {2}));
  view_.onRoadmap(smallRoadmap(7));
  EXPECT_TRUE(view_.releases().second.empty()) << "epoch 5 is a previous traffic manager's";
  view_.onRelease(release("r1", 6, 4, {0, 1}, {2}));
  EXPECT_TRUE(view_.releases().second.empty()) << "late, from an earlier epoch";
  const auto before = view_.releases().first;
  view_.onRelease(release("r1", 7, 1, {0, 1}, {2}));
  view_.onRelease(release("r2", 7, 1, {2}, {}));
  const auto [count, releases] = view_.releases();
  EXPECT_EQ(count, before + 2);
  ASSERT_EQ(releases.size(), 2u);
  EXPECT_EQ(releases.at("r1")->base.size(), 2u);

  const json j = releaseJson(*releases.at("r1"));
  EXPECT_EQ(j["robot"], "r1");
  EXPECT_EQ(j["base"], json::array({0, 1}));
  EXPECT_EQ(j["horizon"], json::array({2}));
  EXPECT_EQ(j["base_xy"], json::array({3.0, 5.0, 4.0, 5.0}));
  EXPECT_EQ(j["horizon_xy"], json::array({6.0, 5.0}));
}

TEST_F(Dash, TheStreamSendsTheRoadmapOnceThenReleasesAndQueuesAsTheyChange) {
  start("");
  view_.onRoadmap(smallRoadmap(7));
  view_.onRelease(release("r1", 7, 1, {0, 1}, {6, 5}));
  view_.onRobot(robot("r2", 5.0, 3.0, 2));  // waiting at the head of P-1's queue
  auto secondRoadmapAt = [](const std::string& got) {
    const auto first = got.find("event: roadmap");
    return first == std::string::npos ? first : got.find("event: roadmap", first + 1);
  };
  // Until the second roadmap and the releases after it have arrived.
  EventStreamReader stream(api_->port(), "/v1/stream", [&](const std::string& got) {
    const auto at = secondRoadmapAt(got);
    return at != std::string::npos && got.find("event: releases", at) != std::string::npos;
  });
  ASSERT_TRUE(snapshotArrived(stream));
  view_.onRelease(release("r1", 7, 2, {1, 6}, {5}));
  view_.onRelease(release("r2", 7, 1, {5}, {}));
  view_.onRobot(robot("r1", 5.0, 4.0, 3));  // joins the queue behind r2
  // A new roadmap starts the releases again: it comes once the stream has sent these changes.
  const bool changesSent = stream.waitFor([](const std::string& got) {
    bool r1 = false;
    bool r2 = false;
    for (const auto& e : eventsNamed(got, "releases")) {
      for (const auto& rel : e["releases"]) {
        r1 = r1 || (rel["robot"] == "r1" && rel["seq"] == 2);
        r2 = r2 || rel["robot"] == "r2";
      }
    }
    const auto queues = eventsNamed(got, "queues");
    return r1 && r2 && !queues.empty() && queues.back()["queues"][0]["waiting"] == json::array({"r2", "r1"});
  });
  ASSERT_TRUE(changesSent) << "the stream did not bring the new releases and queue; it brought:\n"
                           << stream.received();
  view_.onRoadmap(smallRoadmap(9));  // a restarted traffic manager
  ASSERT_TRUE(stream.finish()) << "the stream did not bring the new roadmap and its releases; it brought:\n"
                               << stream.received();
  const std::string got = stream.received();
  const auto roadmaps = eventsNamed(got, "roadmap");
  ASSERT_EQ(roadmaps.size(), 2u) << "the roadmap once, and again when it changed";
  EXPECT_EQ(roadmaps[0]["epoch"], 7);
  EXPECT_EQ(roadmaps[0]["queues"][0]["station"], "node 3") << "the test's site names no station there";
  EXPECT_EQ(roadmaps[1]["epoch"], 9);
  EXPECT_LT(got.find("event: roadmap"), got.find("event: releases")) << "the page needs the nodes first";

  const auto before = eventsNamed(got.substr(0, secondRoadmapAt(got)), "releases");
  ASSERT_GE(before.size(), 2u);
  EXPECT_EQ(before[0]["all"], true) << "the first is the whole set";
  ASSERT_EQ(before[0]["releases"].size(), 1u);
  EXPECT_EQ(before[0]["releases"][0]["horizon"], json::array({6, 5}));
  std::map<std::string, json> changed;
  for (std::size_t i = 1; i < before.size(); ++i) {
    EXPECT_EQ(before[i]["all"], false);
    for (const auto& rel : before[i]["releases"]) {
      const auto id = rel["robot"].get<std::string>();
      EXPECT_FALSE(changed.contains(id)) << "a release sent twice: " << rel;
      changed[id] = rel;
    }
  }
  ASSERT_EQ(changed.size(), 2u) << "only what changed: r1's new release and r2's first";
  EXPECT_EQ(changed["r1"]["seq"], 2);
  EXPECT_EQ(changed["r2"]["base"], json::array({5}));
  const auto after = eventsNamed(got.substr(secondRoadmapAt(got)), "releases");
  ASSERT_EQ(after.size(), 1u);
  EXPECT_EQ(after[0]["all"], true) << "a new roadmap: the set starts again";
  EXPECT_EQ(after[0]["releases"], json::array()) << "the old traffic manager's releases are gone";

  const auto queues = eventsNamed(got, "queues");
  ASSERT_GE(queues.size(), 2u);
  EXPECT_EQ(queues[0]["queues"][0]["waiting"], json::array({"r2"}));
  EXPECT_EQ(queues[1]["queues"][0]["waiting"], json::array({"r2", "r1"}));
  for (std::size_t i = 1; i < queues.size(); ++i) {
    EXPECT_NE(queues[i], queues[i - 1]) << "sent only when who waits changes";
  }

  auto traffic = client_->Get("/v1/traffic");
  ASSERT_TRUE(traffic);
  ASSERT_EQ(traffic->status, 200);
  const json t = json::parse(traffic->body);
  EXPECT_EQ(t["roadmap"]["epoch"], 9);
  EXPECT_EQ(t["releases"], json::array());
  EXPECT_EQ(t["queues"][0]["waiting"], json::array({"r2", "r1"}));
}

namespace {

/// A token file with a read-only and an operator token, and an audit log, in a directory of its own.
class DashScopes : public Dash {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("wms-dash-" + std::to_string(std::random_device{}()));
    fs::create_directories(dir_);
    writeTokens("viewer read " + kViewer + "\nfloor read,operate " + kFloor + "\n");
  }
  void TearDown() override {
    Dash::TearDown();
    fs::remove_all(dir_);
  }
  void writeTokens(const std::string& text) {
    std::ofstream(dir_ / "tokens.new") << text;
    fs::rename(dir_ / "tokens.new", dir_ / "tokens");
  }
  void startWithTokens() {
    ApiSettings s;
    s.tokenFile = (dir_ / "tokens").string();
    s.auditLog = (dir_ / "audit.log").string();
    start(s);
  }
  [[nodiscard]] std::vector<json> auditLines() const {
    std::ifstream in(dir_ / "audit.log");
    std::vector<json> out;
    for (std::string l; std::getline(in, l);) {
      out.push_back(json::parse(l));
    }
    return out;
  }
  httplib::Result pause(const std::pair<std::string, std::string>& session) {
    return client_->Post("/v1/robots/r1/pause", {{"Cookie", session.first}, {kCsrfHeader, session.second}},
                         "", "text/plain");
  }
  const std::string kViewer = "viewer-0123456789abcdef";
  const std::string kFloor = "floor-0123456789abcdef01";
  fs::path dir_;
};

}  // namespace

TEST_F(DashScopes, AReadOnlyTokensSessionReadsButCannotActAndEveryActionIsAudited) {
  startWithTokens();
  const auto viewer = login(kViewer);
  auto robots = client_->Get("/v1/robots", {{"Cookie", viewer.first}});
  ASSERT_TRUE(robots);
  EXPECT_EQ(robots->status, 200);
  auto refused = pause(viewer);
  ASSERT_TRUE(refused);
  EXPECT_EQ(refused->status, 403) << "a session acts with its token's scopes, and \"viewer\" may only read";
  EXPECT_THAT(refused->body, HasSubstr("operate"));
  EXPECT_TRUE(gateway_.seen.empty()) << "a refused action reached the manager";

  const auto floor = login(kFloor);
  auto me = client_->Get("/v1/session", {{"Cookie", floor.first}});
  EXPECT_EQ(json::parse(me->body)["name"], "floor");
  EXPECT_EQ(json::parse(me->body)["scopes"], json::array({"read", "operate"}));
  auto ok = pause(floor);
  ASSERT_TRUE(ok);
  EXPECT_EQ(ok->status, 200) << ok->body;
  EXPECT_EQ(client_
                ->Post("/v1/robots/r2/home", {{"Cookie", floor.first}, {kCsrfHeader, floor.second}}, "",
                       "text/plain")
                ->status,
            201);
  EXPECT_EQ(client_->Delete("/v1/session", {{"Cookie", floor.first}, {kCsrfHeader, floor.second}})->status,
            200);

  const auto lines = auditLines();
  ASSERT_EQ(lines.size(), 6u);  // two logins, the refused pause, the pause, home, logout
  EXPECT_EQ(lines[0]["who"], "viewer");
  EXPECT_EQ(lines[0]["what"]["session"], "login");
  EXPECT_EQ(lines[1]["who"], "viewer");
  EXPECT_EQ(lines[1]["path"], "/v1/robots/r1/pause");
  EXPECT_EQ(lines[1]["status"], 403);
  EXPECT_EQ(lines[3]["who"], "floor");
  EXPECT_EQ(lines[3]["what"], json::parse(R"({"robot": "r1", "action": "pause"})"));
  EXPECT_EQ(lines[4]["what"]["action"], "home");
  EXPECT_EQ(lines[5]["what"]["session"], "logout");
  for (const auto& l : lines) {
    EXPECT_EQ(l.dump().find("0123456789abcdef"), std::string::npos) << "a token in the audit log";
  }

  // The token file decides, also for sessions made before an edit: "floor" removed, its cookie ends.
  writeTokens("viewer read " + kViewer + "\n");
  EXPECT_EQ(client_->Get("/v1/robots", {{"Cookie", floor.first}})->status, 401);
  EXPECT_EQ(client_->Get("/v1/robots", {{"Cookie", viewer.first}})->status, 200);
}

TEST_F(Dash, OpenStreamsHoldNoWorkerAndCountAgainstTheStreamLimit) {
  ApiSettings s;
  s.limits.threads = 2;
  s.limits.maxInFlight = 2;
  s.limits.maxStreams = 6;
  start(s);
  std::vector<std::unique_ptr<RawClient>> pages;
  for (int i = 0; i < 6; ++i) {  // three times the worker threads
    pages.push_back(std::make_unique<RawClient>(api_->port()));
    pages.back()->send("GET /v1/stream HTTP/1.1\r\nHost: x\r\n\r\n");
    ASSERT_THAT(pages.back()->receive("event: snapshot"), HasSubstr("event: snapshot"));
  }
  EXPECT_EQ(api_->serverStats().openStreams.load(), 6);
  client_->set_read_timeout(8, 0);
  auto p = client_->Post("/v1/robots/r1/pause", "", "text/plain");
  ASSERT_TRUE(p) << "POST /v1/robots/r1/pause did not answer with the dashboard's streams open";
  EXPECT_EQ(p->status, 200);
  auto seventh = client_->Get("/v1/stream");
  ASSERT_TRUE(seventh);
  EXPECT_EQ(seventh->status, 503) << "http.max_streams counts the dashboard's streams";
  view_.onRobot(robot("r2", 7.0, 2.0, 3));
  EXPECT_THAT(pages.front()->receive("event: robots"), HasSubstr("event: robots"));
  EXPECT_THAT(pages.back()->receive("event: robots"), HasSubstr("\"x\":7.0"));
}

TEST_F(DashScopes, ThePageIsToldItsScopesAndMarksEveryActionWithTheScopeItNeeds) {
  startWithTokens();
  auto scopesOf = [&](const httplib::Headers& h) {
    auto r = client_->Get("/v1/session", h);
    EXPECT_TRUE(r && r->status == 200);
    return r ? json::parse(r->body)["scopes"] : json();
  };
  EXPECT_EQ(scopesOf({{"Cookie", login(kViewer).first}}), json::array({"read"}));
  EXPECT_EQ(scopesOf({{"Cookie", login(kFloor).first}}), json::array({"read", "operate"}));
  EXPECT_EQ(scopesOf({{"Authorization", "Bearer " + kViewer}}), json::array({"read"}))
      << "a bearer request is told its token's scopes too";

  // The page greys out what the scopes do not allow: each action button says which scope it needs.
  const std::string page = client_->Get("/dashboard/")->body;
  for (const char* action : {"pause", "resume", "home", "charge"}) {
    EXPECT_THAT(page, HasSubstr(std::string("data-robot-action=\"") + action + "\" data-scope=\"operate\""));
  }
  EXPECT_THAT(page, HasSubstr(R"(<button type="submit" data-scope="submit")")) << "the task form";
  const std::string panels = client_->Get("/dashboard/panels.js")->body;
  EXPECT_THAT(panels, HasSubstr("dataset.scope = 'submit'")) << "each task's cancel button";
}

TEST_F(Dash, WithoutAuthenticationThePageMayDoEverything) {
  start("");
  auto r = client_->Get("/v1/session");
  ASSERT_TRUE(r);
  const json s = json::parse(r->body);
  EXPECT_EQ(s["auth"], "off");
  EXPECT_EQ(s["scopes"], json::array({"read", "submit", "operate"}));
}

namespace {
msg::PeopleSeen peopleOf(const std::string& robot, std::int64_t stamp, std::vector<msg::SeenPerson> people) {
  return {robot, stamp, std::move(people)};
}
}  // namespace

TEST_F(Dash, ThePeopleEachRobotSeesAreInTheRobotApiUntilTheirListIsStale) {
  start("");
  const auto now = steadyNowNs();
  ASSERT_TRUE(view_.onPeopleSeen(peopleOf("r1", 1, {{2.004F, 3.0F, 0.5F, 0.0F, 0.25F, true}}), now));
  EXPECT_TRUE(view_.onPeopleSeen(peopleOf("r2", 1, {}), now)) << "seeing nobody is a list too";
  EXPECT_FALSE(view_.onPeopleSeen(peopleOf("r9", 1, {{1, 1, 0, 0, 0.25F, false}}), now));
  EXPECT_EQ(view_.rejections().count("PeopleSeen", "unknown_robot"), 1U);

  const json one = json::parse(client_->Get("/v1/robots/r1")->body);
  ASSERT_EQ(one["people_seen"].size(), 1U);
  EXPECT_DOUBLE_EQ(one["people_seen"][0]["x"].get<double>(), 2.0) << "to the centimetre";
  EXPECT_DOUBLE_EQ(one["people_seen"][0]["vx"].get<double>(), 0.5);
  EXPECT_DOUBLE_EQ(one["people_seen"][0]["radius"].get<double>(), 0.25);
  EXPECT_TRUE(one["people_seen"][0]["velocity_known"].get<bool>());
  EXPECT_EQ(one["people_seen_stamp_ns"], 1);
  const json all = json::parse(client_->Get("/v1/robots")->body);
  ASSERT_EQ(all["robots"].size(), 2U);
  EXPECT_EQ(all["robots"][0]["people_seen"].size(), 1U);
  EXPECT_TRUE(all["robots"][1]["people_seen"].empty());
  EXPECT_FALSE(all["robots"][1]["people_seen_stamp_ns"].is_null());
  const json metrics = json::parse(client_->Get("/v1/metrics")->body);
  EXPECT_EQ(metrics["samples"]["rejected"]["PeopleSeen"]["unknown_robot"], 1);

  // Stale: received too long ago (the robot stopped sending), or far behind the robot's own state.
  ASSERT_TRUE(view_.onPeopleSeen(peopleOf("r1", 1, {{2, 3, 0, 0, 0.25F, false}}),
                                 now - FleetView::kPeopleSeenMaxAgeNs - 1'000'000));
  EXPECT_TRUE(json::parse(client_->Get("/v1/robots/r1")->body)["people_seen"].empty());
  EXPECT_TRUE(json::parse(client_->Get("/v1/robots/r1")->body)["people_seen_stamp_ns"].is_null());
  ASSERT_TRUE(view_.onPeopleSeen(peopleOf("r1", 1, {{2, 3, 0, 0, 0.25F, false}}), steadyNowNs()));
  EXPECT_EQ(json::parse(client_->Get("/v1/robots/r1")->body)["people_seen"].size(), 1U);
  view_.onRobot(robot("r1", 1.0, 1.0, 1 + FleetView::kPeopleSeenMaxAgeNs + 1));
  EXPECT_TRUE(json::parse(client_->Get("/v1/robots/r1")->body)["people_seen"].empty());
}

TEST_F(Dash, ContactsAndNearMissesAreCountedFromTheReportsAndShownInMetricsAndTheStream) {
  start("");
  view_.onRobot(robot("r3", 1.7, 1.0, 1));  // 0.1 m clear of r1: a near miss
  ASSERT_TRUE(view_.onPeopleSeen(peopleOf("r1", 1, {{9.4F, 1.0F, 0, 0, 0.25F, false}}), steadyNowNs()));
  view_.updateProximity(steadyNowNs());  // the person overlaps r2: a contact
  view_.updateProximity(steadyNowNs());
  const json m = json::parse(client_->Get("/v1/metrics")->body)["proximity"];
  EXPECT_EQ(m["robot_robot"]["near_misses"], 1);
  EXPECT_EQ(m["robot_robot"]["contacts"], 0);
  EXPECT_EQ(m["robot_robot"]["close_now"], 1);
  EXPECT_NEAR(m["robot_robot"]["min_clearance_m"].get<double>(), 0.1, 1e-6);
  EXPECT_EQ(m["robot_person"]["contacts"], 1);
  EXPECT_EQ(m["robot_person"]["near_misses"], 1);
  EXPECT_NEAR(m["robot_person"]["min_clearance_m"].get<double>(), -0.15, 1e-6);
  EXPECT_DOUBLE_EQ(m["near_miss_margin_m"].get<double>(), 0.2);

  // A robot not heard of for a while (by the fleet's clock) is no obstacle.
  view_.onRobot(robot("r1", 1.0, 1.0, 1 + FleetView::kLiveRobotNs + 1));
  view_.onRobot(robot("r2", 9.0, 1.0, 1 + FleetView::kLiveRobotNs + 1));
  view_.updateProximity(steadyNowNs());
  EXPECT_EQ(view_.proximity().robotRobot.close, 0U);

  std::string got;
  auto r = client_->Get("/v1/stream", [&](const char* data, std::size_t n) {
    got.append(data, n);
    return got.find("event: proximity") == std::string::npos;
  });
  const auto events = eventsNamed(got, "proximity");
  ASSERT_FALSE(events.empty()) << "sent with the snapshot";
  EXPECT_EQ(events[0]["robot_person"]["contacts"], 1);
}

// The live robot-time ledger: each robot's state samples file the time between them under the
// activity the robot was in; GET /v1/fleet/robot-time answers it (checked against the spec).
TEST_F(Dash, TheRobotTimeLedgerFilesTheTimeBetweenStatesUnderTheEarlierActivity) {
  start("secret");
  auto r1 = robot("r1", 1.0, 1.0, 1);
  r1.activity = fleet::RobotActivity::Driving;
  r1.stamp_ns = 10'000'000'000;
  view_.onRobot(r1);
  r1.stamp_ns += 1'500'000'000;  // 1.5 s driving
  r1.activity = fleet::RobotActivity::WaitingOnRobot;
  view_.onRobot(r1);
  r1.stamp_ns += 500'000'000;  // 0.5 s waiting
  r1.activity = fleet::RobotActivity::Dwelling;
  view_.onRobot(r1);
  r1.stamp_ns += 60'000'000'000;  // silent for a minute: not filed
  view_.onRobot(r1);
  auto res = client_->Get("/v1/fleet/robot-time", {{"Authorization", "Bearer secret"}});
  ASSERT_TRUE(res);
  ASSERT_EQ(res->status, 200) << res->body;
  const auto body = json::parse(res->body);
  const json* mine = nullptr;
  for (const auto& r : body["robots"]) {
    if (r["id"] == "r1") {
      mine = &r;
    }
  }
  ASSERT_NE(mine, nullptr) << body.dump();
  EXPECT_NEAR((*mine)["seconds"].get<double>(), 2.0, 1e-9);
  EXPECT_NEAR((*mine)["by_activity_s"]["driving"].get<double>(), 1.5, 1e-9);
  EXPECT_NEAR((*mine)["shares"]["waiting_on_robot"].get<double>(), 0.25, 1e-9);
  EXPECT_NEAR((*mine)["by_activity_s"]["dwelling"].get<double>(), 0.0, 1e-9);
  double sum = 0.0;
  for (const auto& [k, v] : (*mine)["shares"].items()) {
    sum += v.get<double>();
  }
  EXPECT_NEAR(sum, 1.0, 1e-9);  // the shares add up
  EXPECT_GE(body["fleet"]["seconds"].get<double>(), 2.0);
  // A robot's own state says what it is doing now.
  auto one = client_->Get("/v1/robots/r1", {{"Authorization", "Bearer secret"}});
  ASSERT_TRUE(one && one->status == 200);
  EXPECT_EQ(json::parse(one->body)["activity"], "dwelling");
  // Without a token: refused, as every read route.
  EXPECT_EQ(client_->Get("/v1/fleet/robot-time")->status, 401);
}

// An agent that does not say its activity is read by its mode and task.
TEST(RobotTimeLedger, AnUnsetActivityIsReadFromTheModeAndANewerSampleOnly) {
  fleet::wms::RobotTimeLedger l;
  msg::RobotState s;
  s.robot_id = "a";
  s.mode = msg::RobotMode::Moving;
  s.task_id = "t1";
  s.stamp_ns = 1'000'000'000;
  EXPECT_EQ(fleet::msg::activityOf(s), fleet::RobotActivity::Driving);
  l.onState(s);
  s.stamp_ns = 500'000'000;  // older (delivered late): nothing filed, nothing changed
  l.onState(s);
  s.stamp_ns = 2'000'000'000;
  s.mode = msg::RobotMode::Idle;
  s.task_id.clear();
  l.onState(s);
  EXPECT_NEAR(l.robots().at("a").seconds(fleet::RobotActivity::Driving), 1.0, 1e-9);
  EXPECT_EQ(fleet::msg::activityOf(s), fleet::RobotActivity::NoTask);
  EXPECT_NEAR(l.fleet().total(), 1.0, 1e-9);
}
