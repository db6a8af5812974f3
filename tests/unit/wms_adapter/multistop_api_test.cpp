// Multi-stop tasks through the HTTP API (fake gateway, no DDS): a bad step is a 400 naming its
// path and nothing is sent; a good one reaches the manager with its steps; the stop under way is
// shown on the task. Every response is checked against docs/openapi.yaml.

#include <gtest/gtest.h>

#include "api_fixture.hpp"

using namespace fleet;
using namespace fleet::wms;
using nlohmann::json;
using namespace fleet::wms::testing;

TEST_F(Api, AMultiStopTaskWithABadStepIsRefusedNamingTheStep) {
  start();
  auto r = post(R"({"id": "m-1", "steps": [
      {"action": "pick", "station": "P-1", "load_id": "L-1"},
      {"action": "drop", "station": "D-9", "load_id": "L-1"},
      {"action": "wait"}]})");
  ASSERT_EQ(r->status, 400) << r->body;
  const auto body = json::parse(r->body);
  EXPECT_EQ(body["error"], "invalid");
  ASSERT_EQ(body["fields"].size(), 2u) << r->body;
  EXPECT_EQ(body["fields"][0]["path"], "steps[1].station");
  EXPECT_EQ(body["fields"][0]["reason"], "unknown station 'D-9'");
  EXPECT_EQ(body["fields"][1]["path"], "steps[2].duration_ns");
  r = post(R"({"id": "m-2", "steps": [{"action": "drop", "station": "D-1", "load_id": "L-5"}]})");
  ASSERT_EQ(r->status, 400);
  EXPECT_EQ(json::parse(r->body)["fields"][0]["path"], "steps[0].load_id");
  EXPECT_TRUE(gateway_.stored.empty()) << "nothing of a refused task reaches the manager";
}

TEST_F(Api, AMultiStopTaskReachesTheManagerWithItsStepsAndShowsItsStop) {
  start();
  auto r = post(R"({"id": "m-3", "kind": "multistop", "steps": [
      {"action": "pick", "station": "P-1", "load_id": "L-1", "duration_ns": 1000000000},
      {"action": "drop", "station": "D-1", "load_id": "L-1"},
      {"action": "wait", "duration_ns": 2000000000}]})");
  ASSERT_EQ(r->status, 201) << r->body;
  ASSERT_EQ(gateway_.stored.size(), 1u);
  const auto& sent = gateway_.stored[0];
  EXPECT_EQ(sent.kind, msg::TaskKind::Multistop);
  ASSERT_EQ(sent.steps.size(), 3u);
  EXPECT_EQ(sent.steps[0], (msg::TaskStep{msg::StepAction::Pick, "P-1", "L-1", 1'000'000'000}));
  EXPECT_EQ(sent.steps[2].action, msg::StepAction::Wait);
  msg::TaskEvent e{"m-3", msg::TaskState::EnRoute, "r1", "step 2 of 3: drop L-1 at D-1", 5, 2, ""};
  e.step = 2;
  view_.onEvent(e);
  r = client_->Get("/v1/tasks/m-3");
  ASSERT_EQ(r->status, 200);
  const auto t = json::parse(r->body);
  EXPECT_EQ(t["state"], "en_route");
  EXPECT_EQ(t["step"], 2);
  EXPECT_EQ(t["task"]["steps"].size(), 3u);
  EXPECT_EQ(t["task"]["steps"][1]["load_id"], "L-1");
}
