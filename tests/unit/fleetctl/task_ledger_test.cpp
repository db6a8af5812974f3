#include "task_ledger.hpp"

#include <gtest/gtest.h>

#include <random>

namespace fleet::ctl {
namespace {

constexpr std::int64_t kS = 1000000000;

TEST(TaskLedger, EveryAcknowledgedTaskAccountedFor) {
  TaskLedger l;
  for (const char* id : {"a", "b", "c", "d", "e"}) {
    l.acknowledged(id);
  }
  l.acknowledged("a");  // a re-sent task acknowledged twice (200 duplicate) counts once
  const std::vector<TaskRow> rows = {
      {"a", "done"}, {"b", "failed"}, {"c", "cancelled"}, {"d", "en_route"}, {"x", "queued"}};
  const auto a = l.reconcile(rows, {});
  EXPECT_EQ(a.acknowledged, 5u);
  EXPECT_EQ(a.done, 1u);
  EXPECT_EQ(a.failed, 1u);
  EXPECT_EQ(a.cancelled, 1u);
  EXPECT_EQ(a.active, 1u);
  ASSERT_EQ(a.lost.size(), 1u);  // acknowledged but unknown to the manager
  EXPECT_EQ(a.lost[0], "e");
  EXPECT_EQ(a.unacknowledgedKnown, 1u);  // "x": stored, but the HTTP answer never came
  EXPECT_TRUE(a.duplicated.empty());
}

TEST(TaskLedger, TerminalTwiceIsDuplicated) {
  TaskLedger l;
  l.acknowledged("a");
  l.acknowledged("b");
  const std::vector<TaskRow> rows = {{"a", "done"}, {"b", "done"}};
  const std::vector<TransitionRow> tr = {
      {"a", "queued", 0},    {"b", "queued", 0},    {"a", "assigned", 1 * kS}, {"b", "assigned", 2 * kS},
      {"a", "done", 5 * kS}, {"b", "done", 6 * kS}, {"b", "done", 7 * kS},     {"b", "failed", 8 * kS}};
  const auto a = l.reconcile(rows, tr);
  ASSERT_EQ(a.duplicated.size(), 1u);  // reported once however many extra terminal transitions
  EXPECT_EQ(a.duplicated[0], "b");
  EXPECT_EQ(a.endToEndS.count, 2u);  // only the first "done" of b is a latency sample
  EXPECT_TRUE(a.lost.empty());
}

TEST(TaskLedger, LatenciesFromCreationInSimulatedTime) {
  TaskLedger l;
  l.acknowledged("a");
  l.acknowledged("b");
  const std::vector<TaskRow> rows = {{"a", "done"}, {"b", "queued"}};
  // Stamps on the simulated clock; the first transition of a task is its creation.
  const std::vector<TransitionRow> tr = {{"a", "queued", 10 * kS}, {"a", "assigned", 12 * kS},
                                         {"a", "queued", 15 * kS}, {"a", "assigned", 16 * kS},
                                         {"b", "queued", 20 * kS}, {"b", "assigned", 23 * kS},
                                         {"b", "queued", 25 * kS}, {"a", "done", 40 * kS}};
  const auto a = l.reconcile(rows, tr);
  EXPECT_EQ(a.assignS.count, 2u);  // first assignment per task only
  EXPECT_DOUBLE_EQ(a.assignS.max, 3.0);
  EXPECT_DOUBLE_EQ(a.assignS.p50, 2.0);
  EXPECT_EQ(a.endToEndS.count, 1u);
  EXPECT_DOUBLE_EQ(a.endToEndS.p99, 30.0);
  ASSERT_EQ(a.doneAtS.size(), 1u);
  EXPECT_DOUBLE_EQ(a.doneAtS[0], 40.0);
  EXPECT_EQ(a.active, 1u);
}

// Randomised: the counts always partition the acknowledged set; lost are exactly the ids removed.
// A task stored by a restarted manager before its first Clock message is stamped 0 although the
// log is at 20 s: it must not count as a 20 s assignment latency.
TEST(TaskLedger, UnstampedTasksGiveNoLatency) {
  TaskLedger l;
  l.acknowledged("a");
  l.acknowledged("b");
  const std::vector<TaskRow> rows = {{"a", "done"}, {"b", "en_route"}};
  const std::vector<TransitionRow> tr = {{"a", "queued", 0},         {"a", "assigned", 1 * kS},
                                         {"b", "queued", 0},         {"a", "done", 20 * kS},
                                         {"b", "assigned", 20 * kS}, {"b", "en_route", 21 * kS}};
  // "b" is stored at seq 3 with stamp 0 while the log was at 1 s: within the slack, a real 0.
  const auto a = l.reconcile(rows, tr);
  EXPECT_EQ(a.unstamped, 0u);
  EXPECT_EQ(a.assignS.count, 2u);
  TaskLedger l2;
  l2.acknowledged("c");
  const std::vector<TransitionRow> late = {
      {"a", "queued", 0}, {"a", "assigned", 20 * kS}, {"c", "queued", 0}, {"c", "assigned", 21 * kS}};
  const auto b = l2.reconcile({{"a", "done"}, {"c", "en_route"}}, late);
  EXPECT_EQ(b.unstamped, 1u);
  EXPECT_EQ(b.assignS.count, 1u);  // only "a"; "c" has no trustworthy creation time
  EXPECT_DOUBLE_EQ(b.assignS.max, 20.0);
}

TEST(TaskLedger, RandomisedPartition) {
  std::mt19937 rng(11);
  const char* states[] = {"queued", "assigned", "en_route", "done", "failed", "cancelled"};
  for (int round = 0; round < 50; ++round) {
    TaskLedger l;
    std::vector<TaskRow> rows;
    std::size_t removed = 0;
    const int n = 1 + static_cast<int>(rng() % 200);
    for (int i = 0; i < n; ++i) {
      const std::string id = "t" + std::to_string(i);
      l.acknowledged(id);
      if (rng() % 10 == 0) {
        ++removed;
        continue;
      }
      rows.push_back({id, states[rng() % 6]});
    }
    const auto a = l.reconcile(rows, {});
    EXPECT_EQ(a.lost.size(), removed);
    EXPECT_EQ(a.done + a.failed + a.cancelled + a.active + a.lost.size(), a.acknowledged);
  }
}

TEST(Percentiles, NearestRank) {
  std::vector<double> v;
  for (int i = 100; i >= 1; --i) {
    v.push_back(i);
  }
  const auto p = percentiles(v);
  EXPECT_EQ(p.count, 100u);
  EXPECT_DOUBLE_EQ(p.p50, 50);
  EXPECT_DOUBLE_EQ(p.p90, 90);
  EXPECT_DOUBLE_EQ(p.p99, 99);
  EXPECT_DOUBLE_EQ(p.max, 100);
  const auto one = percentiles({7.0});
  EXPECT_DOUBLE_EQ(one.p50, 7);
  EXPECT_DOUBLE_EQ(one.p99, 7);
  EXPECT_EQ(percentiles({}).count, 0u);
}

}  // namespace
}  // namespace fleet::ctl
