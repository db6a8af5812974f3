#pragma once

// What every TaskStore backend decides the same way, apart from how it reads and writes rows:
// whether a submission is a retry or a conflict, the record a new task starts as, and how a
// transition changes a record. The backends (SQLite, PostgreSQL) load, call these, and store.

#include <cstdint>
#include <optional>
#include <string>

#include "fleet/core/expected.hpp"
#include "fleet/fleet/task_store.hpp"

namespace fleet::store_rules {

/// The schema both backends create and migrate to: version 2 added tasks.paused, version 3
/// tasks.station (the station the dispatcher chose for a charge or park task submitted without
/// one), version 4 tasks.priority and tasks.deadline_ns (the values in force after a change; NULL:
/// as submitted, in the body). A database with a newer version is refused (newerSchema).
inline constexpr int kSchemaVersion = 4;

/// The error for a database whose schema is newer than this binary's, naming both versions.
Error newerSchema(std::string_view where, std::int64_t found);

/// Errors of a task before it is stored (invalid), or empty.
Expected<void> checkSubmission(const Task& t);
/// A stored task submitted again: the same body (a retry) or a conflict. After a change, the body
/// as submitted and the body with the values in force are both the same request.
Expected<void> checkResubmission(const TaskRecord& existing, const std::string& body);
/// A record read with the columns of a change (priority and deadline_ns not NULL): `task` gets the
/// values in force and `submitted` keeps the body's.
void setInForce(TaskRecord& r, const Urgency& inForce);
/// The record a new task is stored as.
TaskRecord newRecord(const Task& t, std::int64_t stampNs);

/// What a transition did: the record after it, and the log row's from-state and robot.
struct Applied {
  TaskRecord record;
  TaskState from = TaskState::Queued;
  std::string logRobot;
};
/// Applies `q` to the stored record `r` (checkTransition with the task's kind, robots, chosen
/// stations) or says why it is refused.
Expected<Applied> applyTransition(TaskRecord r, const TransitionRequest& q);

/// setPaused's checks: not_found is the caller's; illegal_transition for a finished task.
Expected<void> checkPause(const TaskRecord& r);
/// setWaitReason's checks: illegal_transition for a task that is not waiting.
Expected<void> checkWaitReason(const TaskRecord& r);
/// Applies a change to the stored record `r` (the revision grows and updatedNs is the request's
/// when a value differs; changed = false, nothing to write, when none does) or says why it is
/// refused: illegal_transition (not waiting), invalid (a value, or nothing to set).
Expected<ChangeResult> applyChange(TaskRecord r, const ChangeRequest& q);

}  // namespace fleet::store_rules
