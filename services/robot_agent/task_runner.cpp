#include "task_runner.hpp"

#include <algorithm>
#include <utility>

#include "fleet/core/clock.hpp"

namespace fleet::agent {

TaskRunner::OrderChange TaskRunner::accept(const Order& o) {
  if (o.revision == revision_ && o.task == task_) {
    return OrderChange::kSame;
  }
  if (!o.task.empty() && o.goals.empty()) {
    // Nowhere to go: every phase of an order assumes a first goal (the process's edge refuses such
    // orders before; this keeps the runner safe alone). Refused before anything of it is taken.
    refuse(o, "assignment has no goals");
    return OrderChange::kRefused;
  }
  revision_ = o.revision;
  priority_ = o.priority;
  paused_ = o.paused;  // an empty paused order holds the idle robot where it is
  if (o.task.empty()) {
    task_.clear();
    goals_.clear();
    phase_ = Phase::Idle;
    return OrderChange::kCancel;
  }
  if (o.task == task_ && o.goals == goals_) {
    return OrderChange::kPause;
  }
  task_ = o.task;
  goals_ = o.goals;
  goal_ = 0;
  reported_ = TaskState::Assigned;
  phase_ = Phase::Idle;  // started on the next step, which knows the time
  return OrderChange::kNewTask;
}

void TaskRunner::refuse(const Order& o, const std::string& why) {
  if (o.task.empty()) {
    return;
  }
  if (o.task == task_) {
    // Its own task, in a form it cannot carry out: dropped, and reported failed below.
    revision_ = o.revision;
    task_.clear();
    goals_.clear();
    paused_ = false;
    phase_ = Phase::Idle;
    pending_.reset();
  }
  // Another task's order leaves the current task as it was: the robot goes on with it and still
  // reports it (RobotState, TaskStatus), so the fleet manager sees both.
  refusals_.push_back(
      TaskReport{o.task, o.revision, TaskState::Failed, 0.0f, ("refused: " + why).substr(0, 255), o.stampNs});
}

TaskState TaskRunner::stageFor(std::size_t index, bool dwelling) const {
  const auto action = goals_[index].action;
  if (dwelling) {
    if (action == GoalAction::Load) {
      return TaskState::Loading;
    }
    if (action == GoalAction::Unload) {
      return TaskState::Unloading;
    }
  }
  for (std::size_t i = 0; i < index; ++i) {
    if (goals_[i].action == GoalAction::Load) {
      return TaskState::Delivering;
    }
  }
  return TaskState::EnRoute;
}

float TaskRunner::progress() const {
  return goals_.empty() ? 0.0f : static_cast<float>(goal_) / static_cast<float>(goals_.size());
}

std::uint32_t TaskRunner::step() const {
  return goals_.empty() ? 0U : static_cast<std::uint32_t>(std::min(goal_ + 1, goals_.size()));
}

void TaskRunner::reportStage(TaskState st, std::int64_t nowNs) {
  reported_ = st;
  pending_ = TaskReport{task_, revision_, st, progress(), "", nowNs, step()};
}

void TaskRunner::leg(std::int64_t nowNs) {
  phase_ = Phase::Driving;
  phaseStartNs_ = nowNs;
  // Every leg after the first is reported, its stage changed or not: the next stop is news.
  if (const auto st = stageFor(goal_, false); st != reported_ || goal_ > 0) {
    reportStage(st, nowNs);
  }
}

void TaskRunner::arrive(std::int64_t nowNs) {
  phase_ = Phase::Dwelling;
  phaseStartNs_ = nowNs;
  const auto st = stageFor(goal_, true);
  if (st != reported_ && (st == TaskState::Loading || st == TaskState::Unloading)) {
    reportStage(st, nowNs);
  }
}

bool TaskRunner::dwellOver(std::int64_t nowNs) const {
  return nsToSec(nowNs - phaseStartNs_) >= goals_[goal_].dwellS;
}

TaskTick TaskRunner::tick(std::int64_t nowNs) {
  if (phase_ == Phase::Idle && busy()) {
    leg(nowNs);
    return TaskTick::kLegBegan;
  }
  if (phase_ != Phase::Dwelling || !dwellOver(nowNs)) {
    return TaskTick::kNone;
  }
  ++goal_;
  if (goal_ < goals_.size()) {
    leg(nowNs);
    return TaskTick::kLegBegan;
  }
  finish(TaskState::Done, "", nowNs);
  return TaskTick::kDone;
}

void TaskRunner::finish(TaskState final, const std::string& reason, std::int64_t nowNs) {
  pending_ = TaskReport{
      task_, revision_, final, final == TaskState::Done ? 1.0f : 0.0f, reason.substr(0, 255), nowNs, step()};
  task_.clear();
  goals_.clear();
  phase_ = Phase::Idle;
}

void TaskRunner::notice(const std::string& reason, std::int64_t nowNs) {
  if (busy()) {
    pending_ = TaskReport{task_, revision_, reported_, progress(), reason, nowNs, step()};
  }
}

void TaskRunner::shiftClock(std::int64_t heldNs) {
  if (phaseStartNs_ >= 0) {
    phaseStartNs_ += heldNs;
  }
}

std::optional<TaskReport> TaskRunner::takeReport() {
  if (!refusals_.empty()) {
    TaskReport r = std::move(refusals_.front());
    refusals_.erase(refusals_.begin());
    return r;
  }
  if (pending_ && pending_->task.empty()) {
    pending_.reset();
  }
  return std::exchange(pending_, std::nullopt);
}

}  // namespace fleet::agent
