#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "fleet/core/expected.hpp"
#include "fleet/fleet/task.hpp"
#include "fleet/fleet/task_state.hpp"

namespace fleet {

/// How urgent a task is: what a change (TaskStore::change) may set on a waiting task.
struct Urgency {
  std::int32_t priority = 0;
  std::int64_t deadlineNs = 0;  ///< 0 = none
  bool operator==(const Urgency&) const = default;
};

/// A task with where it stands.
struct TaskRecord {
  Task task;
  TaskState state = TaskState::Queued;
  std::string robotId;        ///< robot holding the task while active; empty otherwise
  std::int32_t attempts = 0;  ///< times the task was assigned
  std::string reason;         ///< reason given with the latest transition
  std::int64_t updatedNs = 0;
  std::int64_t revision =
      0;  ///< transitions, changes, pauses and wait reasons applied (the task's events); 1 right after submit
  /// Held by an operator: a waiting task is not dispatched, an active one's robot stands still
  /// with it. Not a state: the task keeps its state and transitions while paused.
  bool paused = false;
  /// `task.station` was chosen by the dispatcher when it assigned the task (a charge or park task
  /// submitted without one). Kept while the task is active and after it ended; cleared when the
  /// task goes back to the queue, as its next robot gets its own choice.
  bool stationChosen = false;
  /// The priority and deadline as submitted, once a change (TaskStore::change) has set others:
  /// `task` holds the values in force. Kept to tell a retry of the submission from a conflict.
  std::optional<Urgency> submitted;
};

/// One row of the append-only transition log. `from` is empty for the submission itself.
struct TransitionRecord {
  std::int64_t seq = 0;
  std::string taskId;
  std::optional<TaskState> from;
  TaskState to = TaskState::Queued;
  std::string robotId;
  std::string reason;
  std::int64_t stampNs = 0;
};

/// `{"task": {…toJson(task)…, "created_ns": …}, "state": "en_route", "robot": "r1", "attempts": 1,
/// "reason": "…", "updated_ns": …, "revision": 3, "paused": false}` — the body of
/// `GET /v1/tasks/{id}`; `"station_chosen": true` is added when the dispatcher chose task.station.
nlohmann::json toJson(const TaskRecord& r);
/// `{"seq": …, "task_id": …, "from": "queued" | null, "to": …, "robot": …, "reason": …, "stamp_ns": …}`
nlohmann::json toJson(const TransitionRecord& t);

struct SubmitResult {
  TaskRecord record;
  bool created = false;  ///< false: the same task was already stored (an idempotent retry)
};

struct TransitionRequest {
  std::string taskId;
  TaskState to = TaskState::Queued;
  /// Required for `assigned`. For later steps, when given it must match the robot holding the task
  /// (error "wrong_robot": a report from a robot that no longer holds it); leave empty for
  /// transitions the manager makes itself (cancel, requeue).
  std::string robotId;
  std::string reason;
  std::int64_t stampNs = 0;
  /// `assigned` only: the station the dispatcher chose for a charge or park task submitted without
  /// one, stored with the assignment in the same commit. Error "invalid" for another kind of task
  /// or one that names its station.
  std::string station;
};

/// A change of a waiting task's priority and/or deadline (PATCH /v1/tasks/{id}).
struct ChangeRequest {
  std::string taskId;
  std::optional<std::int32_t> priority;    ///< in [kMinPriority, kMaxPriority]; unset: kept
  std::optional<std::int64_t> deadlineNs;  ///< >= 0, 0 = none, not before created_ns; unset: kept
  std::int64_t stampNs = 0;
};

/// The problems of a change of task `t` (task_change.cpp): nothing to set, a priority out of
/// range, a negative deadline or one before t's created_ns. Paths "priority" and "deadline_ns".
std::vector<FieldError> validateChange(const ChangeRequest& q, const Task& t);

struct ChangeResult {
  TaskRecord record;
  bool changed = false;  ///< false: the values were already in force (a repeated request)
};

/// Durable tasks: a current-state table and an append-only transition log. Every call that
/// changes state has committed when it returns. Error codes (fleet/fleet/errors.hpp): conflict
/// (same id, different body), not_found, illegal_transition, wrong_robot, invalid, storage.
class TaskStore {
 public:
  virtual ~TaskStore() = default;

  /// Stores a new task as queued (created_ns defaults to `stampNs`). The same id with the same
  /// canonical body returns the stored record with created = false; a different body is a conflict.
  virtual Expected<SubmitResult> submit(const Task& t, std::int64_t stampNs) = 0;
  /// Like submit for each task, all in one transaction and one durable commit (group commit).
  /// Items are independent: a conflict fails that item only. If the commit fails, every item
  /// fails with "storage" and nothing is stored.
  virtual std::vector<Expected<SubmitResult>> submitBatch(const std::vector<Task>& tasks,
                                                          std::int64_t stampNs) = 0;

  /// Applies one legal transition (checkTransition with the task's kind) and logs it.
  virtual Expected<TaskRecord> transition(const TransitionRequest& r) = 0;
  Expected<TaskRecord> transition(std::string_view taskId, TaskState to, std::string_view robotId,
                                  std::string_view reason, std::int64_t stampNs) {
    return transition(
        TransitionRequest{std::string(taskId), to, std::string(robotId), std::string(reason), stampNs, {}});
  }
  /// Several transitions in one commit; each is checked against the state left by the ones before.
  virtual std::vector<Expected<TaskRecord>> transitionBatch(const std::vector<TransitionRequest>& rs) = 0;

  /// Sets the task's `paused` flag durably (not a transition: the log is unchanged, but the
  /// revision grows, as the task's events count it: a restarted manager numbers its next event
  /// after the pause's). Errors: not_found; illegal_transition for a task already done, failed or
  /// cancelled.
  virtual Expected<TaskRecord> setPaused(std::string_view id, bool paused, std::int64_t stampNs) = 0;
  /// Sets the reason of a waiting task (why it still waits) durably, without a transition (the
  /// revision grows, as the task's events count it). Errors: not_found; illegal_transition for a
  /// task that is not queued or requeued.
  virtual Expected<TaskRecord> setWaitReason(std::string_view id, std::string_view reason,
                                             std::int64_t stampNs) = 0;
  /// Sets a waiting (queued or requeued) task's priority and/or deadline durably; not a transition
  /// (the log is unchanged) but the revision grows, as the task's events count it. The body as
  /// submitted is kept: a re-submission is the same request when it equals that body or the body
  /// with the values in force (store_rules::checkResubmission). Values already in force change
  /// nothing (changed = false). Errors: not_found; illegal_transition for a task that is not
  /// waiting (the message names its state); invalid for a value out of range, a deadline before
  /// the task's created_ns, or a request that sets neither.
  virtual Expected<ChangeResult> change(const ChangeRequest& r) = 0;

  virtual Expected<TaskRecord> get(std::string_view id) = 0;
  /// Tasks in `state` (all when empty) ordered by id, at most `limit`, with ids after `afterId`.
  virtual Expected<std::vector<TaskRecord>> list(std::optional<TaskState> state, std::size_t limit,
                                                 std::string_view afterId = {}) = 0;
  /// Every task not done, failed or cancelled, oldest first: what a restarted manager rebuilds from.
  virtual Expected<std::vector<TaskRecord>> openTasks() = 0;
  virtual Expected<std::vector<TransitionRecord>> history(std::string_view id) = 0;
  virtual Expected<std::map<TaskState, std::int64_t>> countByState() = 0;
};

}  // namespace fleet
