#include "task_store_rules.hpp"

#include "fleet/core/ids.hpp"
#include "fleet/fleet/errors.hpp"

namespace fleet::store_rules {

Error newerSchema(std::string_view where, std::int64_t found) {
  return Error{errc::kSchemaNewer, std::string(where) + " has schema version " + std::to_string(found) +
                                       ", newer than this binary's version " +
                                       std::to_string(kSchemaVersion) +
                                       ": run a fleet manager of the version that wrote it (or newer)"};
}

Expected<void> checkSubmission(const Task& t) {
  if (auto errs = validateTask(t); !errs.empty()) {
    return unexpected(errc::kInvalid, makeValidationError(std::move(errs)).message);
  }
  return {};
}

Expected<void> checkResubmission(const TaskRecord& existing, const std::string& body) {
  Task inForce = existing.task;
  if (existing.stationChosen) {
    inForce.station.clear();
  }
  if (canonicalBody(inForce) == body) {
    return {};
  }
  if (existing.submitted) {
    Task asSubmitted = inForce;
    asSubmitted.priority = existing.submitted->priority;
    asSubmitted.deadlineNs = existing.submitted->deadlineNs;
    if (canonicalBody(asSubmitted) == body) {
      return {};
    }
  }
  return unexpected(errc::kConflict, "task '" + existing.task.id + "' already exists with a different body");
}

void setInForce(TaskRecord& r, const Urgency& inForce) {
  r.submitted = Urgency{r.task.priority, r.task.deadlineNs};
  r.task.priority = inForce.priority;
  r.task.deadlineNs = inForce.deadlineNs;
}

TaskRecord newRecord(const Task& t, std::int64_t stampNs) {
  TaskRecord r;
  r.task = t;
  if (r.task.createdNs == 0) {
    r.task.createdNs = stampNs;
  }
  r.state = TaskState::Queued;
  r.reason = "submitted";
  r.updatedNs = stampNs;
  r.revision = 1;
  return r;
}

Expected<Applied> applyTransition(TaskRecord r, const TransitionRequest& q) {
  if (auto ok = checkTransition(r.state, q.to, r.task.kind); !ok) {
    return unexpected(errc::kIllegalTransition, "task '" + q.taskId + "': " + ok.error().message);
  }
  if (q.to == TaskState::Assigned) {
    if (q.robotId.empty()) {
      return unexpected(errc::kInvalid, "task '" + q.taskId + "': assigning needs a robot id");
    }
    if (!r.task.robot.empty() && r.task.robot != q.robotId) {
      return unexpected(errc::kWrongRobot,
                        "task '" + q.taskId + "' may only be assigned to robot '" + r.task.robot + "'");
    }
    r.robotId = q.robotId;
    ++r.attempts;
  } else if (!q.robotId.empty() && q.robotId != r.robotId) {
    return unexpected(errc::kWrongRobot, "task '" + q.taskId + "' is not held by robot '" + q.robotId + "'");
  }
  if (!q.station.empty()) {
    if (q.to != TaskState::Assigned) {
      return unexpected(errc::kInvalid, "task '" + q.taskId + "': a station is chosen only when assigning");
    }
    if (r.task.kind != TaskKind::Charge && r.task.kind != TaskKind::Park) {
      return unexpected(errc::kInvalid,
                        "task '" + q.taskId + "': only charge and park tasks get a chosen station");
    }
    if (!r.task.station.empty() && !r.stationChosen) {
      return unexpected(errc::kInvalid, "task '" + q.taskId + "' names its station");
    }
    if (!isValidId(q.station)) {
      return unexpected(errc::kInvalid, "task '" + q.taskId + "': not a valid station id");
    }
    r.task.station = q.station;
    r.stationChosen = true;
  } else if (isWaiting(q.to) && r.stationChosen) {
    // Back in the queue: the next robot gets the station nearest to it.
    r.task.station.clear();
    r.stationChosen = false;
  }
  Applied a;
  a.from = r.state;
  a.logRobot = q.robotId.empty() ? r.robotId : q.robotId;
  r.state = q.to;
  if (!isActive(q.to)) {
    // Only an active task has a robot; the log keeps who held it.
    r.robotId.clear();
  }
  r.reason = q.reason;
  r.updatedNs = q.stampNs;
  ++r.revision;
  a.record = std::move(r);
  return a;
}

Expected<void> checkPause(const TaskRecord& r) {
  if (isTerminal(r.state)) {
    return unexpected(errc::kIllegalTransition,
                      "task '" + r.task.id + "' is already " + std::string(toString(r.state)));
  }
  return {};
}

Expected<void> checkWaitReason(const TaskRecord& r) {
  if (!isWaiting(r.state)) {
    return unexpected(errc::kIllegalTransition,
                      "task '" + r.task.id + "' is " + std::string(toString(r.state)) + ", not waiting");
  }
  return {};
}

Expected<ChangeResult> applyChange(TaskRecord r, const ChangeRequest& q) {
  if (!isWaiting(r.state)) {
    return unexpected(errc::kIllegalTransition,
                      "task '" + r.task.id + "' is " + std::string(toString(r.state)) +
                          "; only a waiting (queued or requeued) task can be changed");
  }
  if (auto errs = validateChange(q, r.task); !errs.empty()) {
    return unexpected(errc::kInvalid, makeValidationError(std::move(errs)).message);
  }
  const Urgency now{q.priority.value_or(r.task.priority), q.deadlineNs.value_or(r.task.deadlineNs)};
  if (now == Urgency{r.task.priority, r.task.deadlineNs}) {
    return ChangeResult{std::move(r), false};  // idempotent: nothing to write
  }
  if (!r.submitted) {
    r.submitted = Urgency{r.task.priority, r.task.deadlineNs};
  }
  r.task.priority = now.priority;
  r.task.deadlineNs = now.deadlineNs;
  r.updatedNs = q.stampNs;
  ++r.revision;
  return ChangeResult{std::move(r), true};
}

}  // namespace fleet::store_rules
