// PATCH /v1/tasks/{id}: a waiting task's priority and deadline changed through the adapter. The
// body is checked before anything is sent (400 naming the field); the manager's answer becomes
// 200 with the values in force, 409 naming the state of a task that no longer waits, 404, or 503;
// the change event updates the task's view and is logged for the event stream and webhooks.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "api_fixture.hpp"
#include "json_schema_check.hpp"
#include "rfc3339.hpp"

using namespace fleet;
using namespace fleet::wms;
using namespace fleet::wms::testing;
using nlohmann::json;
using ::testing::HasSubstr;

namespace {

/// The manager's answer to a change it stored: the values in force (as the node's ack says).
msg::TaskAck stored(const msg::Task& r, bool changed = true) {
  const json d = {{"priority", r.set_priority ? r.priority : 0},
                  {"deadline_ns", r.set_deadline ? r.deadline_ns : 0},
                  {"changed", changed},
                  {"revision", 2}};
  return {r.request_id, r.task_id, msg::AckResult::Stored, msg::TaskState::Queued, d.dump(), 0};
}

class TaskChangeApi : public Api {
 protected:
  httplib::Result patch(const std::string& id, const std::string& body) {
    return client_->Patch("/v1/tasks/" + id, body, "application/json");
  }
  /// The field paths of a 400's body.
  static std::vector<std::string> paths(const httplib::Result& r) {
    std::vector<std::string> out;
    const json body = json::parse(r->body);
    for (const auto& f : body.value("fields", json::array())) {
      out.push_back(f["path"]);
    }
    return out;
  }
};

}  // namespace

TEST_F(TaskChangeApi, APriorityAndAnRfc3339DeadlineReachTheManagerAndTheAnswerHasTheValuesInForce) {
  gateway_.onControl = [](const msg::Task& r) { return stored(r); };
  start();
  auto r = patch("t-1", R"({"priority": 7, "deadline": "2026-12-02T14:05:00Z"})");
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 200) << r->body;
  ASSERT_EQ(gateway_.controlRequests.size(), 1u);
  const auto& sent = gateway_.controlRequests[0];
  EXPECT_EQ(sent.control, msg::TaskControl::Change);
  EXPECT_EQ(sent.task_id, "t-1");
  EXPECT_TRUE(sent.set_priority);
  EXPECT_EQ(sent.priority, 7);
  EXPECT_TRUE(sent.set_deadline);
  const auto deadline = parseRfc3339("2026-12-02T14:05:00Z", nullptr);
  EXPECT_EQ(sent.deadline_ns, *deadline);
  EXPECT_FALSE(sent.request_id.empty());
  const auto body = json::parse(r->body);
  EXPECT_EQ(body["id"], "t-1");
  EXPECT_EQ(body["state"], "queued");
  EXPECT_EQ(body["priority"], 7);
  EXPECT_EQ(body["deadline_ns"], *deadline);
  EXPECT_EQ(body["deadline"], "2026-12-02T14:05:00Z");
  EXPECT_EQ(body["changed"], true);

  // One of the two: the other is not sent as set (the manager keeps it).
  r = patch("t-1", R"({"deadline_ns": 0})");
  ASSERT_EQ(r->status, 200) << r->body;
  EXPECT_FALSE(gateway_.controlRequests[1].set_priority);
  EXPECT_TRUE(gateway_.controlRequests[1].set_deadline);
  EXPECT_EQ(gateway_.controlRequests[1].deadline_ns, 0);
  EXPECT_FALSE(json::parse(r->body).contains("deadline")) << "no deadline: no text";
}

TEST_F(TaskChangeApi, BadValuesAre400NamingTheFieldAndNothingIsSent) {
  gateway_.onControl = [](const msg::Task& r) { return stored(r); };
  start();
  const std::vector<std::pair<std::string, std::string>> cases = {
      {R"({"priority": "high"})", "priority"},
      {R"({"priority": 1001})", "priority"},
      {R"({"priority": 1.5})", "priority"},
      {R"({"deadline_ns": -1})", "deadline_ns"},
      {R"({"deadline_ns": "soon"})", "deadline_ns"},
      {R"({"deadline": "tomorrow"})", "deadline"},
      {R"({"deadline": "2026-12-02T14:05:00Z", "deadline_ns": 5})", "deadline"},
      {R"({"priority": 1, "kind": "goto"})", "kind"},
      {R"({})", ""},
      {R"([1, 2])", ""},
      {R"({"priority": )", ""},
  };
  for (const auto& [body, field] : cases) {
    auto r = patch("t-1", body);
    ASSERT_TRUE(r);
    EXPECT_EQ(r->status, 400) << body << " -> " << r->body;
    EXPECT_THAT(paths(r), ::testing::Contains(field)) << body << " -> " << r->body;
  }
  auto r = patch("a%20b", R"({"priority": 1})");
  EXPECT_EQ(r->status, 400);
  EXPECT_THAT(paths(r), ::testing::Contains("id"));
  EXPECT_TRUE(gateway_.controlRequests.empty()) << "nothing reached the manager";
}

TEST_F(TaskChangeApi, TheManagersRefusalsBecome409NamingTheState404400And503) {
  gateway_.onControl = [](const msg::Task& r) -> msg::TaskAck {
    if (r.task_id == "busy") {
      return {r.request_id,
              r.task_id,
              msg::AckResult::Refused,
              msg::TaskState::EnRoute,
              "task 'busy' is en_route; only a waiting (queued or requeued) task can be changed",
              0};
    }
    if (r.task_id == "early") {
      return {r.request_id,
              r.task_id,
              msg::AckResult::Invalid,
              msg::TaskState::Rejected,
              R"j([{"path":"deadline_ns","reason":"is before the task's created_ns (5)"}])j",
              0};
    }
    if (r.task_id == "down") {
      return {r.request_id, r.task_id, msg::AckResult::Unavailable, msg::TaskState::Rejected, "storage", 0};
    }
    return {r.request_id, r.task_id, msg::AckResult::NotFound, msg::TaskState::Rejected, "no task", 0};
  };
  start();
  auto r = patch("busy", R"({"priority": 3})");
  ASSERT_EQ(r->status, 409) << r->body;
  EXPECT_EQ(json::parse(r->body)["state"], "en_route");
  EXPECT_THAT(json::parse(r->body)["message"].get<std::string>(), HasSubstr("is en_route"));
  r = patch("early", R"({"deadline_ns": 1})");
  ASSERT_EQ(r->status, 400) << r->body;
  EXPECT_EQ(paths(r), std::vector<std::string>{"deadline_ns"});
  EXPECT_EQ(patch("down", R"({"priority": 3})")->status, 503);
  EXPECT_EQ(patch("nope", R"({"priority": 3})")->status, 404);
  gateway_.silent = true;
  r = patch("busy", R"({"priority": 3})");
  EXPECT_EQ(r->status, 503);
  EXPECT_EQ(r->get_header_value("Retry-After"), "2");
  gateway_.silent = false;
  gateway_.online = false;
  r = patch("busy", R"({"priority": 3})");
  EXPECT_EQ(r->status, 503);
  EXPECT_THAT(r->body, HasSubstr("nothing was changed"));
}

TEST_F(TaskChangeApi, TheChangeEventUpdatesTheTaskViewAndIsLoggedWithTheNewValues) {
  start();
  ASSERT_EQ(
      post(R"({"id": "t-1", "kind": "transport", "pickup": "P-1", "dropoff": "D-1", "priority": 2})")->status,
      201);
  msg::TaskEvent e{"t-1", msg::TaskState::Queued, "", "changed by request: priority 9, deadline_ns 0", 5, 2,
                   ""};
  e.changed = true;
  e.priority = 9;
  e.deadline_ns = 4'000'000'000'000'000'000;
  view_.onEvent(e);
  auto r = client_->Get("/v1/tasks/t-1");
  ASSERT_EQ(r->status, 200) << r->body;
  const auto task = json::parse(r->body)["task"];
  EXPECT_EQ(task["priority"], 9);
  EXPECT_EQ(task["deadline_ns"], 4'000'000'000'000'000'000);
  EXPECT_EQ(task["deadline"], toRfc3339(4'000'000'000'000'000'000));
  EXPECT_EQ(task["pickup"], "P-1") << "the rest as submitted";

  // A later change to priority 0 and no deadline: the task JSON leaves both out, as submissions do.
  e.seq = 3;
  e.priority = 0;
  e.deadline_ns = 0;
  view_.onEvent(e);
  const auto after = json::parse(client_->Get("/v1/tasks/t-1")->body)["task"];
  EXPECT_FALSE(after.contains("priority"));
  EXPECT_FALSE(after.contains("deadline_ns"));

  // The event stream's and webhooks' form: the values beside the transition's fields, and it
  // conforms to the spec's TaskEvent.
  const auto logged = api_->eventLog().after(0, 10);
  ASSERT_EQ(logged.size(), 2u);
  const auto j = loggedEventJson(logged[0]);
  EXPECT_EQ(j["changed"], true);
  EXPECT_EQ(j["priority"], 9);
  EXPECT_EQ(j["deadline"], toRfc3339(4'000'000'000'000'000'000));
  const test::SchemaCheck schema(test::OpenApiContract::shipped().document());
  EXPECT_TRUE(schema.problems(j, {{"$ref", "#/components/schemas/TaskEvent"}}).empty());
  EXPECT_FALSE(loggedEventJson(logged[1]).contains("deadline"));
}

TEST(TaskChangeLog, ChangesSurviveInAnEventLogFileAndAnOlderFileGetsTheColumns) {
  // An event log as the adapter wrote it before changes were logged.
  const auto now = wallNowNs();
  const std::string path = writeOlderEventLog("wms_change", "", now);
  {
    EventLog log({path}, std::make_shared<SqliteDb>(path));
    msg::TaskEvent e{"old", msg::TaskState::Queued, "", "changed", 2, 2, ""};
    e.changed = true;
    e.priority = -4;
    e.deadline_ns = 77;
    EXPECT_EQ(log.append({e}, now), 1u);
  }
  EventLog log({path}, std::make_shared<SqliteDb>(path));
  const auto all = log.after(0, 10);
  ASSERT_EQ(all.size(), 2u);
  EXPECT_FALSE(all[0].event.changed) << "the old row is not a change";
  EXPECT_TRUE(all[1].event.changed);
  EXPECT_EQ(all[1].event.priority, -4);
  EXPECT_EQ(all[1].event.deadline_ns, 77);
  std::filesystem::remove_all(std::filesystem::path(path).parent_path());
}
