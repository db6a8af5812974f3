#include "fleet/fleet/task_reconciler.hpp"

#include <gtest/gtest.h>

#include <map>

using namespace fleet;

namespace {
constexpr std::int64_t kS = 1'000'000'000;

/// The manager's side: robot -> the task it has the robot carry.
struct Store {
  std::map<std::string, std::string> carries;
  std::string operator()(const std::string& robot) const {
    const auto it = carries.find(robot);
    return it == carries.end() ? std::string() : it->second;
  }
};
}  // namespace

TEST(TaskReconciler, AgreeingReportsAreNotTracked) {
  TaskReconciler rec(5 * kS);
  Store store{{{"r1", "t1"}}};
  for (std::int64_t t = 0; t < 20 * kS; t += kS / 2) {
    rec.observe("r1", "t1", store("r1"), t);
    rec.observe("r2", "", store("r2"), t);
    EXPECT_TRUE(rec.due(t, store).empty());
  }
  EXPECT_EQ(rec.tracked(), 0u);
}

TEST(TaskReconciler, ARobotReportingNoTaskForTheGraceIsMissingItsTask) {
  TaskReconciler rec(5 * kS);
  Store store{{{"r1", "t1"}}};
  for (std::int64_t t = kS; t < 6 * kS; t += kS / 2) {
    rec.observe("r1", "", store("r1"), t);
    EXPECT_TRUE(rec.due(t, store).empty()) << t;
  }
  rec.observe("r1", "", store("r1"), 6 * kS);
  const auto due = rec.due(6 * kS, store);
  ASSERT_EQ(due.size(), 1u);
  EXPECT_EQ(due[0].kind, TaskMismatch::Kind::Missing);
  EXPECT_EQ(due[0].robot, "r1");
  EXPECT_EQ(due[0].expected, "t1");
  EXPECT_EQ(due[0].reported, "");
  EXPECT_EQ(due[0].sinceNs, kS);
  // Unresolved (the caller could not act): asked again only after another grace.
  EXPECT_TRUE(rec.due(7 * kS, store).empty());
  EXPECT_EQ(rec.due(11 * kS, store).size(), 1u);
}

TEST(TaskReconciler, ReportingTheTaskWithinTheGraceEndsTheDisagreement) {
  TaskReconciler rec(5 * kS);
  Store store;
  // The manager assigns t1 at 1 s; the robot's states show no task until the order reaches it.
  store.carries["r1"] = "t1";
  for (std::int64_t t = kS; t < 5 * kS; t += kS / 2) {
    rec.observe("r1", "", store("r1"), t);
    EXPECT_TRUE(rec.due(t, store).empty());
  }
  rec.observe("r1", "t1", store("r1"), 5 * kS);
  for (std::int64_t t = 5 * kS; t < 30 * kS; t += kS) {
    EXPECT_TRUE(rec.due(t, store).empty()) << t;
  }
  EXPECT_EQ(rec.tracked(), 0u);
}

TEST(TaskReconciler, ANewRecordRestartsTheGraceFromTheNextReport) {
  TaskReconciler rec(5 * kS);
  Store store{{{"r1", "t1"}}};
  rec.observe("r1", "", store("r1"), 0);
  // At 4 s the manager gives r1 another task (t1 finished, t2 assigned): the reports before
  // do not count against t2.
  store.carries["r1"] = "t2";
  EXPECT_TRUE(rec.due(4 * kS, store).empty());
  rec.observe("r1", "", store("r1"), 4 * kS + 100);
  EXPECT_TRUE(rec.due(6 * kS, store).empty()) << "t2's grace started at 4 s, not 0";
  EXPECT_TRUE(rec.due(9 * kS, store).empty());
  const auto due = rec.due(9 * kS + 100, store);
  ASSERT_EQ(due.size(), 1u);
  EXPECT_EQ(due[0].expected, "t2");
  EXPECT_EQ(due[0].sinceNs, 4 * kS + 100);
  // The caller requeued t2: the robot carries nothing now, and reports nothing: settled.
  store.carries.erase("r1");
  EXPECT_TRUE(rec.due(10 * kS, store).empty());
  EXPECT_EQ(rec.tracked(), 0u);
}

TEST(TaskReconciler, ARobotReportingAnotherTaskIsMissingItsOwnAndReportsAnUnexpectedOneOnce) {
  TaskReconciler rec(5 * kS);
  Store store{{{"r1", "t1"}}};
  for (std::int64_t t = 0; t <= 5 * kS; t += kS) {
    rec.observe("r1", "old", store("r1"), t);
  }
  auto due = rec.due(5 * kS, store);
  ASSERT_EQ(due.size(), 2u);
  EXPECT_EQ(due[0].kind, TaskMismatch::Kind::Missing);
  EXPECT_EQ(due[0].reported, "old");
  EXPECT_EQ(due[1].kind, TaskMismatch::Kind::Unexpected);
  EXPECT_EQ(due[1].reported, "old");
  EXPECT_EQ(due[1].expected, "t1");
  EXPECT_EQ(due[1].sinceNs, 0);
  // t1 requeued; the robot goes on reporting "old": a new record, a new grace, one more report.
  store.carries.erase("r1");
  EXPECT_TRUE(rec.due(6 * kS, store).empty());
  for (std::int64_t t = 6 * kS; t < 11 * kS; t += kS) {
    rec.observe("r1", "old", store("r1"), t);
    EXPECT_TRUE(rec.due(t, store).empty()) << t;
  }
  due = rec.due(11 * kS, store);
  ASSERT_EQ(due.size(), 1u);
  EXPECT_EQ(due[0].kind, TaskMismatch::Kind::Unexpected);
  EXPECT_EQ(due[0].sinceNs, 6 * kS);
  for (std::int64_t t = 12 * kS; t < 30 * kS; t += kS) {
    rec.observe("r1", "old", store("r1"), t);
    EXPECT_TRUE(rec.due(t, store).empty()) << "said once";
  }
}

TEST(TaskReconciler, AReportOfATaskJustEndedIsNotUnexpectedWithinTheGrace) {
  TaskReconciler rec(5 * kS);
  Store store{{{"r1", "t1"}}};
  for (std::int64_t t = 0; t < 60 * kS; t += kS) {
    rec.observe("r1", "t1", store("r1"), t);
  }
  // t1 ends at 60 s (charged, cancelled): the robot reports it until its empty order arrives.
  store.carries.erase("r1");
  EXPECT_TRUE(rec.due(60 * kS, store).empty());
  rec.observe("r1", "t1", store("r1"), 60 * kS + 1);
  EXPECT_TRUE(rec.due(62 * kS, store).empty());
  rec.observe("r1", "", store("r1"), 62 * kS);
  EXPECT_TRUE(rec.due(90 * kS, store).empty());
  EXPECT_EQ(rec.tracked(), 0u);
}

TEST(TaskReconciler, AForgottenRobotIsNotReported) {
  TaskReconciler rec(5 * kS);
  Store store{{{"r1", "t1"}}};
  rec.observe("r1", "", store("r1"), 0);
  rec.forget("r1");
  EXPECT_TRUE(rec.due(10 * kS, store).empty());
  EXPECT_EQ(rec.tracked(), 0u);
}
