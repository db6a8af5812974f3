// Task times as RFC 3339 beside their ns: parsed and written exactly, refused naming the field,
// accepted in POST /v1/tasks and shown in what the API returns.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "api_fixture.hpp"
#include "rfc3339.hpp"
#include "task_times.hpp"

using namespace fleet;
using namespace fleet::wms;
using namespace fleet::wms::testing;
using nlohmann::json;
using ::testing::HasSubstr;

TEST(Rfc3339, ReadsAndWritesUtcAndOffsetsToTheNanosecond) {
  EXPECT_EQ(parseRfc3339("1970-01-01T00:00:00Z", nullptr), 0);
  EXPECT_EQ(parseRfc3339("2026-12-02T14:05:00Z", nullptr), 1'796'220'300'000'000'000LL);
  EXPECT_EQ(parseRfc3339("2026-12-02T15:05:00+01:00", nullptr), 1'796'220'300'000'000'000LL);
  EXPECT_EQ(parseRfc3339("2026-12-02t14:05:00.25z", nullptr), 1'796'220'300'250'000'000LL);
  EXPECT_EQ(parseRfc3339("2024-02-29T00:00:00.000000001-00:30", nullptr), 1'709'166'600'000'000'001LL);
  EXPECT_EQ(toRfc3339(1'796'220'300'000'000'000LL), "2026-12-02T14:05:00Z");
  EXPECT_EQ(toRfc3339(1'796'220'300'250'000'000LL), "2026-12-02T14:05:00.250Z");
  EXPECT_EQ(toRfc3339(1'796'220'300'000'001'000LL), "2026-12-02T14:05:00.000001Z");
  EXPECT_EQ(toRfc3339(1'709'166'600'000'000'001LL), "2024-02-29T00:30:00.000000001Z");
  for (const std::int64_t ns :
       {0LL, 1LL, 999'999'999LL, 1'796'220'300'123'456'789LL, 9'000'000'000'000'000'000LL}) {
    EXPECT_EQ(parseRfc3339(toRfc3339(ns), nullptr), ns) << toRfc3339(ns);
  }
  std::string why;
  EXPECT_FALSE(parseRfc3339("2026-12-02 14:05", &why));
  EXPECT_THAT(why, HasSubstr("RFC 3339"));
  EXPECT_FALSE(parseRfc3339("2026-02-30T00:00:00Z", &why));
  EXPECT_THAT(why, HasSubstr("out of range"));
  EXPECT_FALSE(parseRfc3339("2026-12-02T14:05:00", &why));
  EXPECT_THAT(why, HasSubstr("no offset"));
  EXPECT_FALSE(parseRfc3339("2026-12-02T14:05:00.Z", &why));
  EXPECT_THAT(why, HasSubstr("fraction"));
  EXPECT_FALSE(parseRfc3339("1969-12-31T23:59:59Z", &why));
  EXPECT_THAT(why, HasSubstr("outside"));
  EXPECT_FALSE(parseRfc3339("2026-12-02T14:05:00+0100", &why));
  EXPECT_FALSE(parseRfc3339("2026-12-02T14:05:00Zjunk", &why));
}

TEST(TaskTimes, TextReplacesNsAndIsRefusedNamingTheField) {
  json one = {{"id", "a"}, {"deadline", "2026-12-02T14:05:00Z"}};
  EXPECT_TRUE(acceptTaskTimes(one).empty());
  EXPECT_EQ(one, json::parse(R"({"id": "a", "deadline_ns": 1796220300000000000})"));
  json batch = {
      {"tasks",
       {{{"id", "a"}, {"created", "yesterday"}},
        {{"id", "b"}, {"deadline", "2026-12-02T14:05:00Z"}, {"deadline_ns", 5}},
        {{"id", "c"}, {"deadline", "2026-12-02T14:05:00Z"}, {"deadline_ns", 1796220300000000000}}}}};
  const auto errs = acceptTaskTimes(batch);
  ASSERT_EQ(errs.size(), 2U);
  EXPECT_EQ(errs[0].path, "tasks[0].created");
  EXPECT_THAT(errs[0].reason, HasSubstr("RFC 3339"));
  EXPECT_EQ(errs[1].path, "tasks[1].deadline");
  EXPECT_THAT(errs[1].reason, HasSubstr("differs from deadline_ns"));
  json arr = json::array({{{"id", "a"}, {"deadline", 5}}});
  EXPECT_EQ(acceptTaskTimes(arr).at(0).path, "[0].deadline");
  json shown = {{"id", "a"}, {"deadline_ns", 1796220300000000000}, {"created_ns", 0}};
  showTaskTimes(shown);
  EXPECT_EQ(shown["deadline"], "2026-12-02T14:05:00Z");
  EXPECT_FALSE(shown.contains("created"));
}

namespace {
class TaskTimesApi : public Api {};
}  // namespace

TEST_F(TaskTimesApi, PostedAsTextAndReturnedAsBoth) {
  start();
  auto r = post(R"({"id": "t-1", "kind": "transport", "pickup": "P-1", "dropoff": "D-1",
                    "deadline": "2030-01-01T01:00:00+01:00", "created": "2029-12-31T23:00:00Z"})");
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 201) << r->body;
  EXPECT_EQ(gateway_.bodies.size(), 1U);
  r = client_->Get("/v1/tasks/t-1");
  ASSERT_EQ(r->status, 200);
  const auto v = json::parse(r->body);
  EXPECT_EQ(v["task"]["deadline_ns"], 1'893'456'000'000'000'000LL);
  EXPECT_EQ(v["task"]["deadline"], "2030-01-01T00:00:00Z");
  EXPECT_EQ(v["task"]["created"], "2029-12-31T23:00:00Z");
  EXPECT_EQ(v["updated"], toRfc3339(v["updated_ns"].get<std::int64_t>()));
  // The same task with its deadline as ns is the same task (a duplicate, not a conflict).
  r = post(R"({"id": "t-1", "kind": "transport", "pickup": "P-1", "dropoff": "D-1",
               "deadline_ns": 1893456000000000000, "created": "2029-12-31T23:00:00Z"})");
  EXPECT_EQ(r->status, 200) << r->body;
  r = post(R"({"tasks": [{"id": "t-2", "kind": "transport", "pickup": "P-1", "dropoff": "D-1",
                          "deadline": "tomorrow"}]})");
  ASSERT_EQ(r->status, 400);
  const auto b = json::parse(r->body);
  EXPECT_EQ(b["fields"][0]["path"], "tasks[0].deadline");
  EXPECT_THAT(b["fields"][0]["reason"].get<std::string>(), HasSubstr("RFC 3339"));
  const auto list = json::parse(client_->Get("/v1/tasks")->body);
  EXPECT_EQ(list["tasks"][0]["task"]["deadline"], "2030-01-01T00:00:00Z");
}
