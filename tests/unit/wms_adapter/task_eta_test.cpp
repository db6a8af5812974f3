// The task's ETA in the API: the manager's estimate (TaskEvent.eta_ns) shown on the task's view
// as eta_ns and RFC 3339, carried by the event stream and webhooks, and kept by the event log
// (a log written before ETAs gets the column).

#include <gtest/gtest.h>

#include <filesystem>

#include "api_fixture.hpp"
#include "json_schema_check.hpp"
#include "rfc3339.hpp"

using namespace fleet;
using namespace fleet::wms;
using namespace fleet::wms::testing;
using nlohmann::json;

namespace {
constexpr std::int64_t kEta = 1'800'000'000'000'000'000;  // 2027-01-15T08:00:00Z
}

TEST_F(Api, TheTasksViewAndItsLoggedEventStateTheEta) {
  start();
  ASSERT_EQ(post(R"({"id": "t-1", "kind": "transport", "pickup": "P-1", "dropoff": "D-1"})")->status, 201);
  msg::TaskEvent e{"t-1", msg::TaskState::Assigned, "r-1", "allocated", 5, 2, ""};
  e.eta_ns = kEta;
  view_.onEvent(e);
  auto r = client_->Get("/v1/tasks/t-1");
  ASSERT_EQ(r->status, 200) << r->body;
  const auto j = json::parse(r->body);
  EXPECT_EQ(j["eta_ns"], kEta);
  EXPECT_EQ(j["eta"], toRfc3339(kEta));
  const test::SchemaCheck schema(test::OpenApiContract::shipped().document());
  EXPECT_TRUE(schema.problems(j, {{"$ref", "#/components/schemas/TaskView"}}).empty()) << j.dump();

  const auto logged = api_->eventLog().after(0, 10);
  ASSERT_EQ(logged.size(), 1u);
  const auto ev = loggedEventJson(logged[0]);
  EXPECT_EQ(ev["eta_ns"], kEta);
  EXPECT_EQ(ev["eta"], toRfc3339(kEta));
  EXPECT_TRUE(schema.problems(ev, {{"$ref", "#/components/schemas/TaskEvent"}}).empty()) << ev.dump();

  // Failed: no estimate any more, and the view says none rather than keeping the old one.
  e.seq = 3;
  e.state = msg::TaskState::Failed;
  e.eta_ns = 0;
  view_.onEvent(e);
  const auto after = json::parse(client_->Get("/v1/tasks/t-1")->body);
  EXPECT_FALSE(after.contains("eta_ns"));
  EXPECT_FALSE(after.contains("eta"));
  EXPECT_FALSE(loggedEventJson(api_->eventLog().after(0, 10).back()).contains("eta_ns"));
}

TEST(TaskEtaLog, AnOlderEventLogGetsTheColumnAndKeepsItsRows) {
  // The log as the adapter wrote it before events carried an ETA (with the change columns).
  const auto now = wallNowNs();
  const std::string path = writeOlderEventLog("wms_eta", ", priority INTEGER, deadline_ns INTEGER", now);
  {
    EventLog log({path}, std::make_shared<SqliteDb>(path));
    msg::TaskEvent e{"old", msg::TaskState::Assigned, "r-1", "allocated", 2, 2, ""};
    e.eta_ns = kEta;
    EXPECT_EQ(log.append({e}, now), 1u);
  }
  EventLog log({path}, std::make_shared<SqliteDb>(path));
  const auto all = log.after(0, 10);
  ASSERT_EQ(all.size(), 2u);
  EXPECT_EQ(all[0].event.eta_ns, 0) << "the old row has no estimate";
  EXPECT_EQ(all[1].event.eta_ns, kEta);
  std::filesystem::remove_all(std::filesystem::path(path).parent_path());
}

TEST_F(Api, EventsOfAnOlderManagerEpochChangeNoViewLogOrStream) {
  // A standby manager took over (epoch 5); the one it fenced off (epoch 4) still sends an event.
  start();
  msg::TaskEvent fresh{"t-1", msg::TaskState::Assigned, "r-1", "allocated", 5, 2, ""};
  fresh.epoch = 5;
  view_.onEvent(fresh);
  msg::TaskEvent stale{"t-1", msg::TaskState::Cancelled, "", "old manager", 6, 9, ""};
  stale.epoch = 4;
  view_.onEvent(stale);
  const auto j = json::parse(client_->Get("/v1/tasks/t-1")->body);
  EXPECT_EQ(j["state"], "assigned") << "the newer epoch's view stands";
  EXPECT_EQ(api_->eventLog().after(0, 10).size(), 1u) << "the stale event is not logged";
  EXPECT_EQ(view_.staleEpochEvents(), 1u);
  const auto metrics = json::parse(client_->Get("/v1/metrics")->body);
  EXPECT_EQ(metrics["event_log"]["stale_epoch_events"], 1);
}
