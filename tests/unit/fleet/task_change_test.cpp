// TaskStore::change on every backend (Backends/TaskStoreTest, fixture in task_store_fixture.hpp):
// a waiting task's priority and deadline changed durably, refused for any other state, and what a
// re-submission after a change is.

#include <gtest/gtest.h>

#include "task_store_fixture.hpp"

namespace fleet::store_test {
namespace {

ChangeRequest change(std::string id, std::optional<std::int32_t> priority,
                     std::optional<std::int64_t> deadline, std::int64_t stamp) {
  return {std::move(id), priority, deadline, stamp};
}

TEST_P(TaskStoreTest, AWaitingTasksPriorityAndDeadlineChangeDurably) {
  {
    auto store = open();
    ASSERT_TRUE(store->submit(transport("t1", 2), 10));
    auto c = store->change(change("t1", 7, std::nullopt, 20));
    ASSERT_TRUE(c) << c.error().message;
    EXPECT_TRUE(c->changed);
    EXPECT_EQ(c->record.task.priority, 7);
    EXPECT_EQ(c->record.task.deadlineNs, 0) << "not given: kept";
    EXPECT_EQ(c->record.revision, 2) << "the revision counts the change";
    EXPECT_EQ(c->record.updatedNs, 20);
    ASSERT_TRUE(c->record.submitted);
    EXPECT_EQ(c->record.submitted->priority, 2);
    EXPECT_EQ(store->history("t1")->size(), 1u) << "not a transition";

    auto d = store->change(change("t1", std::nullopt, 5'000, 30));
    ASSERT_TRUE(d) << d.error().message;
    EXPECT_EQ(d->record.task.priority, 7);
    EXPECT_EQ(d->record.task.deadlineNs, 5'000);
    EXPECT_EQ(d->record.submitted->priority, 2) << "still the values as submitted";
    EXPECT_EQ(d->record.submitted->deadlineNs, 0);

    // Idempotent: the values in force again change nothing.
    auto same = store->change(change("t1", 7, 5'000, 40));
    ASSERT_TRUE(same) << same.error().message;
    EXPECT_FALSE(same->changed);
    EXPECT_EQ(same->record.revision, 3);
    EXPECT_EQ(same->record.updatedNs, 30);
  }
  auto store = open();  // a restart
  const auto got = store->get("t1");
  ASSERT_TRUE(got) << got.error().message;
  EXPECT_EQ(got->task.priority, 7);
  EXPECT_EQ(got->task.deadlineNs, 5'000);
  EXPECT_EQ(got->revision, 3);
  ASSERT_TRUE(got->submitted);
  EXPECT_EQ(*got->submitted, (Urgency{2, 0}));
  EXPECT_EQ(store->openTasks()->front().task.priority, 7);
  EXPECT_EQ(store->list(std::nullopt, 10)->front().task.deadlineNs, 5'000);
  EXPECT_EQ(toJson(*got)["task"]["priority"], 7) << "the API shows the values in force";
  // Transitions keep the values in force.
  auto a = store->transition("t1", TaskState::Assigned, "r1", "", 50);
  ASSERT_TRUE(a) << a.error().message;
  EXPECT_EQ(a->task.priority, 7);
  EXPECT_EQ(a->revision, 4);
  EXPECT_EQ(store->get("t1")->task.deadlineNs, 5'000);
}

TEST_P(TaskStoreTest, AChangeIsRefusedUnlessTheTaskWaits) {
  auto store = open();
  EXPECT_EQ(store->change(change("nope", 1, std::nullopt, 1)).error().code, errc::kNotFound);
  ASSERT_TRUE(store->submit(transport("t1"), 1));
  ASSERT_TRUE(store->transition("t1", TaskState::Assigned, "r1", "", 2));
  auto active = store->change(change("t1", 5, std::nullopt, 3));
  ASSERT_FALSE(active);
  EXPECT_EQ(active.error().code, errc::kIllegalTransition);
  EXPECT_NE(active.error().message.find("is assigned"), std::string::npos) << active.error().message;
  // Back in the queue (requeued), it waits again and may be changed.
  ASSERT_TRUE(store->transition("t1", TaskState::Requeued, "", "robot r1 lost", 4));
  auto requeued = store->change(change("t1", 5, std::nullopt, 5));
  ASSERT_TRUE(requeued) << requeued.error().message;
  EXPECT_EQ(requeued->record.task.priority, 5);
  ASSERT_TRUE(store->transition("t1", TaskState::Cancelled, "", "", 6));
  auto done = store->change(change("t1", 6, std::nullopt, 7));
  ASSERT_FALSE(done);
  EXPECT_EQ(done.error().code, errc::kIllegalTransition);
  EXPECT_NE(done.error().message.find("is cancelled"), std::string::npos) << done.error().message;
  EXPECT_EQ(store->get("t1")->task.priority, 5) << "nothing written";
}

TEST_P(TaskStoreTest, AChangeWithBadValuesIsInvalidAndWritesNothing) {
  auto store = open();
  Task t = transport("t1");
  t.createdNs = 1'000;
  ASSERT_TRUE(store->submit(t, 1'000));
  for (const auto& [q, field] : {std::pair{change("t1", std::nullopt, std::nullopt, 2), "priority"},
                                 std::pair{change("t1", kMaxPriority + 1, std::nullopt, 2), "priority"},
                                 std::pair{change("t1", std::nullopt, -1, 2), "deadline_ns"},
                                 std::pair{change("t1", std::nullopt, 999, 2), "deadline_ns"}}) {
    auto r = store->change(q);
    ASSERT_FALSE(r) << field;
    EXPECT_EQ(r.error().code, errc::kInvalid);
    EXPECT_NE(r.error().message.find(field), std::string::npos) << r.error().message;
  }
  const auto got = store->get("t1");
  EXPECT_EQ(got->revision, 1);
  EXPECT_FALSE(got->submitted);
  auto clear = store->change(change("t1", std::nullopt, 0, 3));
  ASSERT_TRUE(clear) << "0 clears the deadline";
  EXPECT_FALSE(clear->changed) << "there was none";
}

TEST_P(TaskStoreTest, AResubmissionAfterAChangeIsTheSameRequestAsSubmittedOrAsInForce) {
  auto store = open();
  Task t = transport("t1", 2);
  t.deadlineNs = 9'000;
  ASSERT_TRUE(store->submit(t, 1));
  ASSERT_TRUE(store->change(change("t1", 8, 0, 2)));
  // The WMS retries its original POST: the same request, and the values in force stay.
  auto retry = store->submit(t, 3);
  ASSERT_TRUE(retry) << retry.error().message;
  EXPECT_FALSE(retry->created);
  EXPECT_EQ(retry->record.task.priority, 8) << "a retry does not undo the change";
  EXPECT_EQ(retry->record.task.deadlineNs, 0);
  // A WMS that updated its copy with the change posts the values in force: the same request too.
  Task inForce = t;
  inForce.priority = 8;
  inForce.deadlineNs = 0;
  auto updated = store->submit(inForce, 4);
  ASSERT_TRUE(updated) << updated.error().message;
  EXPECT_FALSE(updated->created);
  // Anything else is a conflict, as before a change.
  Task other = t;
  other.priority = 5;
  EXPECT_EQ(store->submit(other, 5).error().code, errc::kConflict);
  Task half = t;
  half.priority = 8;  // the new priority with the old deadline: neither body
  EXPECT_EQ(store->submit(half, 6).error().code, errc::kConflict);
  store.reset();
  auto reopened = open();
  EXPECT_FALSE(reopened->submit(t, 7)->created) << "after a restart too";
}

}  // namespace
}  // namespace fleet::store_test
