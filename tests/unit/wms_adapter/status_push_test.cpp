// The event log and the resumable event stream (docs/operator-guide.md#status-push): ids grow by
// one per transition and are never reused, a transition heard twice is logged once, a stream
// resumes after Last-Event-ID or ?since= with nothing missed or repeated (also across an adapter
// restart), and an id past the retention is refused naming the field.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <regex>

#include "../fleet/temp_dir.hpp"
#include "api_fixture.hpp"
#include "event_stream_reader.hpp"

using namespace fleet;
using namespace fleet::wms;
using namespace fleet::wms::testing;
using nlohmann::json;
using ::testing::ElementsAre;
using ::testing::HasSubstr;

namespace {

msg::TaskEvent ev(const std::string& task, std::uint32_t seq,
                  msg::TaskState state = msg::TaskState::Assigned) {
  return {task, state, "r1", "", static_cast<std::int64_t>(seq) * 1000, seq, ""};
}

std::vector<std::int64_t> idsOf(const std::vector<LoggedEvent>& events) {
  std::vector<std::int64_t> out;
  for (const auto& e : events) {
    out.push_back(e.id);
  }
  return out;
}

/// The ids of the `id:` lines of an event stream's text, in order.
std::vector<std::int64_t> streamIds(const std::string& text) {
  std::vector<std::int64_t> out;
  const std::regex line(R"((?:^|\n)id: (\d+)\n)");
  for (auto it = std::sregex_iterator(text.begin(), text.end(), line); it != std::sregex_iterator(); ++it) {
    out.push_back(std::stoll((*it)[1]));
  }
  return out;
}

EventLog memoryLog(EventLogSettings s = {}) {
  return EventLog(s, std::make_shared<SqliteDb>(s.path));
}

}  // namespace

TEST(EventLog, IdsGrowByOneAndATransitionHeardTwiceIsLoggedOnce) {
  auto log = memoryLog();
  EXPECT_EQ(log.append({ev("t-1", 1), ev("t-1", 2), ev("t-2", 1)}, 1), 3U);
  // The manager's history to a late joiner and its announcement after a restart: same task, same seq.
  EXPECT_EQ(log.append({ev("t-1", 2), ev("t-2", 1), ev("t-2", 2)}, 2), 1U);
  EXPECT_EQ(log.lastId(), 4);
  const auto all = log.after(0, 100);
  EXPECT_THAT(idsOf(all), ElementsAre(1, 2, 3, 4));
  EXPECT_EQ(all[3].event.task_id, "t-2");
  EXPECT_EQ(all[3].event.seq, 2U);
  EXPECT_THAT(idsOf(log.after(2, 1)), ElementsAre(3));
  EXPECT_TRUE(log.after(4, 10).empty());
  EXPECT_EQ(loggedEventJson(all[0]),
            json::parse(R"({"event_id": 1, "id": "t-1", "state": "assigned", "robot": "r1", "reason": "",
                            "stamp_ns": 1000, "seq": 1, "station": ""})"));
}

TEST(EventLog, AReopenedFileKeepsItsIdsAndWhatItHasHeard) {
  fleet::test::TempDir dir;
  EventLogSettings s;
  s.path = dir.file("events.db");
  {
    EventLog log(s, std::make_shared<SqliteDb>(s.path));
    log.append({ev("t-1", 1), ev("t-1", 2), ev("t-1", 3)}, 1);
  }
  EventLog log(s, std::make_shared<SqliteDb>(s.path));
  EXPECT_TRUE(log.durable());
  EXPECT_EQ(log.lastId(), 3);
  EXPECT_EQ(log.append({ev("t-1", 3)}, 2), 0U) << "announced again after a restart: logged once";
  log.append({ev("t-1", 4, msg::TaskState::Done)}, 3);
  EXPECT_THAT(idsOf(log.after(1, 10)), ElementsAre(2, 3, 4));
}

TEST(EventLog, RetentionKeepsTheNewestAndSaysWhatIsGone) {
  EventLogSettings s;
  s.retainEvents = 100;
  auto log = memoryLog(s);
  for (std::uint32_t i = 1; i <= 500; ++i) {
    log.append({ev("t-" + std::to_string(i), 1)}, i);
  }
  EXPECT_EQ(log.lastId(), 500);
  EXPECT_GE(log.prunedThrough(), 399);
  EXPECT_LE(log.prunedThrough(), 400);
  // Asked from before the retention: what is held, from the oldest held on (the stream and the
  // webhooks check prunedThrough first and say so).
  EXPECT_EQ(log.after(0, 1).at(0).id, log.prunedThrough() + 1);
  // By age: nothing older than retain_seconds once a second has passed.
  EventLogSettings aged;
  aged.retainSeconds = 10;
  auto old = memoryLog(aged);
  old.append({ev("a", 1), ev("b", 1)}, 0);
  old.append({ev("c", 1)}, 20'000'000'000);
  EXPECT_EQ(old.prunedThrough(), 2);
  EXPECT_THAT(idsOf(old.after(2, 10)), ElementsAre(3));
}

TEST(EventLog, ReadsFromDiskWhatTheMemoryNoLongerHolds) {
  fleet::test::TempDir dir;
  EventLogSettings s;
  s.path = dir.file("events.db");
  EventLog log(s, std::make_shared<SqliteDb>(s.path));
  std::vector<msg::TaskEvent> batch;
  for (std::size_t i = 0; i < EventLog::kMemoryTail + 100; ++i) {
    batch.push_back(ev("t-" + std::to_string(i), 1));
  }
  log.append(batch, 1);
  EXPECT_THAT(idsOf(log.after(0, 3)), ElementsAre(1, 2, 3));
  EXPECT_EQ(log.after(0, 3)[2].event.task_id, "t-2");
  const auto lastTwo = log.after(log.lastId() - 2, 10);
  EXPECT_EQ(lastTwo.size(), 2U);
}

namespace {

class StatusPush : public Api {
 protected:
  /// Stops the API (as an adapter that exits) and starts a new one with `s`.
  void restart(ApiSettings s) {
    api_->stop();
    thread_.join();
    spec_.report();
    api_.reset();
    start(std::move(s));
  }
  /// An event stream's text until `until` appears (or 5 s), from a raw connection.
  std::string stream(const std::string& target, const std::string& headers, const std::string& until) {
    RawClient c(api_->port());
    EXPECT_TRUE(c.connected());
    c.send("GET " + target + " HTTP/1.1\r\nHost: localhost\r\n" + headers + "\r\n");
    return c.receive(until, std::chrono::seconds(5));
  }
  fleet::test::TempDir dir_;
};

}  // namespace

TEST_F(StatusPush, AStreamSendsIdsAndResumesAfterLastEventIdWithNothingMissedOrRepeated) {
  start();
  // Without since= or Last-Event-ID the stream starts after the newest event when the server
  // handles the request: publish only once it has answered.
  EventStreamReader reader(api_->port(), "\"seq\":3");
  ASSERT_TRUE(reader.waitOpen()) << "GET /v1/events did not answer 200 with an open stream";
  view_.onEvent(ev("t-1", 1));
  view_.onEvent(ev("t-1", 2));
  view_.onEvent(ev("t-1", 3));
  ASSERT_TRUE(reader.finish()) << "the stream did not bring the third event; it brought:\n"
                               << reader.received();
  const auto& first = reader.received();
  ASSERT_THAT(streamIds(first), ElementsAre(1, 2, 3)) << first;
  EXPECT_THAT(first, HasSubstr("id: 2\nevent: task\ndata: {\"event_id\":2,\"id\":\"t-1\""));
  // Disconnected after 2 (as a client that lost its connection mid-stream); meanwhile 3 more.
  view_.onEvent(ev("t-1", 4));
  view_.onEvent(ev("t-1", 4));  // heard twice: one event
  view_.onEvent(ev("t-2", 1));
  view_.onEvent(ev("t-1", 5, msg::TaskState::Done));
  const auto resumed = stream("/v1/events", "Last-Event-ID: 2\r\n", "id: 6\n");
  EXPECT_THAT(streamIds(resumed), ElementsAre(3, 4, 5, 6)) << resumed;
  const auto since = stream("/v1/events?since=4", "", "id: 6\n");
  EXPECT_THAT(streamIds(since), ElementsAre(5, 6));
  // Last-Event-ID (the browser's reconnect) wins over the URL's since.
  const auto both = stream("/v1/events?since=1", "Last-Event-ID: 5\r\n", "id: 6\n");
  EXPECT_THAT(streamIds(both), ElementsAre(6));
}

TEST_F(StatusPush, AStreamResumesAcrossAnAdapterRestart) {
  ApiSettings s;
  s.events.path = dir_.file("events.db");
  start(s);
  view_.onEvent(ev("t-1", 1));
  view_.onEvent(ev("t-1", 2));
  view_.onEvent(ev("t-2", 1));
  restart(s);
  // What DDS hands the restarted adapter: the manager's history (heard before) and new events.
  view_.onEvent(ev("t-1", 2));
  view_.onEvent(ev("t-2", 1));
  view_.onEvent(ev("t-2", 2));
  view_.onEvent(ev("t-1", 3, msg::TaskState::Done));
  const auto resumed = stream("/v1/events", "Last-Event-ID: 1\r\n", "id: 5\n");
  EXPECT_THAT(streamIds(resumed), ElementsAre(2, 3, 4, 5)) << resumed;
  EXPECT_THAT(resumed, HasSubstr("id: 5\nevent: task\ndata: {\"event_id\":5,\"id\":\"t-1\""));
  EXPECT_THAT(resumed, HasSubstr("\"seq\":3,\"stamp_ns\":3000,\"state\":\"done\""));
}

TEST_F(StatusPush, AnIdPastTheRetentionOrNotAnIdIsRefusedNamingTheField) {
  ApiSettings s;
  s.events.retainEvents = 3;
  start(s);
  for (std::uint32_t i = 1; i <= 10; ++i) {
    view_.onEvent(ev("t-" + std::to_string(i), 1));
  }
  const auto pruned = api_->eventLog().prunedThrough();
  ASSERT_GE(pruned, 6);
  httplib::Headers h = {{"Last-Event-ID", "1"}};
  auto r = client_->Get("/v1/events", h);
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 410);
  auto body = json::parse(r->body);
  EXPECT_EQ(body["error"], "expired");
  EXPECT_EQ(body["fields"][0]["path"], "Last-Event-ID");
  EXPECT_THAT(body["fields"][0]["reason"].get<std::string>(),
              AllOf(HasSubstr("the events after 1 up to " + std::to_string(pruned)),
                    HasSubstr("events.retain_events"), HasSubstr("since=" + std::to_string(pruned))));
  r = client_->Get("/v1/events?since=2");
  EXPECT_EQ(r->status, 410);
  EXPECT_EQ(json::parse(r->body)["fields"][0]["path"], "since");
  r = client_->Get("/v1/events?since=abc");
  EXPECT_EQ(r->status, 400);
  EXPECT_EQ(json::parse(r->body)["fields"][0]["path"], "since");
  r = client_->Get("/v1/events?since=99");
  EXPECT_EQ(r->status, 400);
  EXPECT_THAT(json::parse(r->body)["fields"][0]["reason"].get<std::string>(),
              AllOf(HasSubstr("ahead of this adapter's newest event 10"), HasSubstr("events.log")));
  // From the oldest held on: served.
  const auto ok = stream("/v1/events?since=" + std::to_string(pruned), "", "id: 10\n");
  EXPECT_EQ(streamIds(ok).front(), pruned + 1);
  EXPECT_EQ(streamIds(ok).back(), 10);
}

TEST_F(StatusPush, EventsAndWebhookSettingsAreReadAndCheckedFromTheConfig) {
  auto cfg =
      Config::fromJson(json::parse(R"({"events": {"log": "/var/lib/fleet/events.db", "retain_events": 50},
      "webhooks": {"allow": ["https://wms.example/hooks"], "max_attempts": 3}})"),
                       "test");
  const auto s = readApiSettings(cfg);
  EXPECT_EQ(s.events.path, "/var/lib/fleet/events.db");
  EXPECT_EQ(s.events.retainEvents, 50);
  EXPECT_EQ(s.webhooks.allow, std::vector<std::string>{"https://wms.example/hooks"});
  EXPECT_EQ(s.webhooks.maxAttempts, 3);
  auto bad = Config::fromJson(json::parse(R"({"events": {"retain": 5}, "webhooks": {"allow": ["ftp://x"]}})"),
                              "test");
  readApiSettings(bad);
  EXPECT_THAT(bad.problems(), ::testing::Contains(HasSubstr("events.retain")));
  EXPECT_THAT(bad.problems(),
              ::testing::Contains(AllOf(HasSubstr("webhooks.allow"), HasSubstr("only http and https"))));
  ApiSettings unopenable;
  unopenable.events.path = dir_.file("no/such/dir/events.db");
  EXPECT_THROW(HttpApi(unopenable, stations_, gateway_, view_, clock_), ConfigError);
  // Another program's database (the manager's task store) is refused, not written into.
  ApiSettings foreign;
  foreign.events.path = dir_.file("fleet.db");
  SqliteDb(foreign.events.path).exec("CREATE TABLE tasks(id TEXT PRIMARY KEY)");
  try {
    HttpApi api(foreign, stations_, gateway_, view_, clock_);
    ADD_FAILURE() << "a foreign database was taken as the event log";
  } catch (const ConfigError& e) {
    EXPECT_THAT(e.what(), AllOf(HasSubstr("events.log"), HasSubstr("is not the adapter's event log"),
                                HasSubstr("\"tasks\"")));
  }
}

// What logging costs the intake: events appended in the batches the DDS gateway takes (20 here) to
// a file log. A bound far above the figure (docs/benchmarks.md gives it): the test catches a log
// that syncs or scans per event, not a slow machine.
TEST(EventLog, AppendsFarFasterThanTheManagerPublishes) {
  for (const int batchSize : {20, 1}) {
    fleet::test::TempDir dir;
    EventLogSettings s;
    s.path = dir.file("events.db");
    s.retainEvents = 2'000;  // pruning by count runs too
    EventLog log(s, std::make_shared<SqliteDb>(s.path));
    const int events = batchSize == 1 ? 5'000 : 20'000;
    const auto t0 = std::chrono::steady_clock::now();
    for (int b = 0; b < events / batchSize; ++b) {
      std::vector<msg::TaskEvent> batch;
      for (int i = 0; i < batchSize; ++i) {
        batch.push_back(ev("t-" + std::to_string(b * batchSize + i), 1));
      }
      log.append(batch, 1);
    }
    const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const double rate = events / secs;
    std::printf("event log: %d events in batches of %d to a file in %.3f s: %.0f events/s\n", events,
                batchSize, secs, rate);
    EXPECT_EQ(log.lastId(), events);
    EXPECT_GE(log.prunedThrough(), events - 2'021);
    EXPECT_GT(rate, 2000.0) << "batches of " << batchSize;
  }
}
