#pragma once

// The robot's task state machine: the order it carries (goals with their actions and dwell
// times), where it is in it, and the task states it reports. It is the only part that changes
// phase: the agent tells it what happened (an order came, the robot arrived at its goal, the task
// failed) and calls tick() once a cycle, which begins the first leg of a new order and ends each
// dwell (on to the next goal, or the task is done). Its types are its own: the agent maps the wire's.
//
//   Idle ──tick()──► Driving ──arrive()──► Dwelling ──tick(): dwell over──► Driving ... ──► Idle
//
// Reports follow the task: Assigned on a new order, EnRoute / Delivering when a leg begins (once
// per change, and at every leg after the first, so each stop of a multi-stop order is told),
// Loading / Unloading on arriving at such a goal, Done / Failed at the end. Each report names the
// goal it is about (step, from 1).

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "fleet/core/pose2.hpp"
#include "fleet/core/task_state.hpp"

namespace fleet::agent {

enum class GoalAction : std::uint8_t { None, Load, Unload, Charge, Park };

struct TaskGoal {
  Pose2 pose;
  std::string station;
  GoalAction action = GoalAction::None;
  double dwellS = 0.0;
  std::string loadId{};  ///< the load a pick (Load) or drop (Unload) goal handles; may be empty
  bool operator==(const TaskGoal&) const = default;
};

struct TaskReport {
  std::string task;
  std::uint32_t revision = 0;
  TaskState stage = TaskState::Queued;
  float progress = 0.0f;  ///< goals done / goals
  std::string reason;     ///< why it failed, or a notice (sensor loss); at most 255 bytes
  std::int64_t stampNs = 0;
  std::uint32_t step = 0;  ///< the goal the robot is at or driving to, from 1 (the last when done); 0: none
};

struct Order {
  std::string task;  ///< empty: cancel
  std::uint32_t revision = 0;
  std::vector<TaskGoal> goals;
  bool paused = false;
  std::int64_t stampNs = 0;   ///< when it was issued (a refusal is reported with it)
  std::int32_t priority = 0;  ///< the task's (higher first)
};

enum class Phase : std::uint8_t { Idle, Driving, Dwelling };

/// What tick() did.
enum class TaskTick : std::uint8_t {
  kNone,      ///< nothing changed
  kLegBegan,  ///< a leg began: the first of a new order, or the next goal's after a dwell
  kDone,      ///< the last dwell ended: the task is done (reported)
};

class TaskRunner {
 public:
  enum class OrderChange : std::uint8_t {
    kSame,     ///< the order again (transient-local re-delivery): nothing changes
    kCancel,   ///< no task any more
    kPause,    ///< the same task, held or resumed (or re-published after a manager restart)
    kNewTask,  ///< a new task (or new goals): starts on the next step
    kRefused,  ///< a task with no goals: refused (reported failed); another task it had goes on
  };
  /// A new revision replaces the current order, and any order replaces the trip home.
  OrderChange accept(const Order& o);

  /// An order that cannot be carried out (refused at the process's edge, or without goals): reports
  /// task `o.task` failed with "refused: <why>". Only an order for the current task drops it; one
  /// for another task leaves the current task as it was.
  void refuse(const Order& o, const std::string& why);

  /// Once a cycle: a new order's first leg begins (Idle with a task), and a dwell that is over
  /// ends, once: the next goal's leg begins, or, after the last goal, the task is done.
  TaskTick tick(std::int64_t nowNs);
  /// At the current goal while driving to it: Dwelling; reports Loading / Unloading for such goals.
  void arrive(std::int64_t nowNs);
  [[nodiscard]] bool dwellOver(std::int64_t nowNs) const;
  /// The task ends: reports `final` with `reason`; Idle.
  void finish(TaskState final, const std::string& reason, std::int64_t nowNs);
  /// A notice about the task in its current stage (e.g. sensor loss), if there is a task.
  void notice(const std::string& reason, std::int64_t nowNs);
  /// The operator's hold lasted `heldNs`: the phase's clock starts that much later.
  void shiftClock(std::int64_t heldNs);
  /// The report due, if any (taken once; refusals first).
  std::optional<TaskReport> takeReport();

  [[nodiscard]] Phase phase() const { return phase_; }
  [[nodiscard]] std::int64_t phaseStartNs() const { return phaseStartNs_; }
  /// Carries a task of the manager's.
  [[nodiscard]] bool busy() const { return !task_.empty(); }
  /// Held by the operator: with a task (paused), or idle (a robot hold: it stays where it is).
  [[nodiscard]] bool paused() const { return paused_; }
  [[nodiscard]] const std::string& task() const { return task_; }
  /// The running task's priority (0 without a task): reserved traffic lets it go first.
  [[nodiscard]] std::int32_t priority() const { return busy() ? priority_ : 0; }
  [[nodiscard]] std::uint32_t revision() const { return revision_; }
  [[nodiscard]] std::size_t goalIndex() const { return goal_; }
  [[nodiscard]] bool hasGoal() const { return goal_ < goals_.size(); }
  /// The current goal (hasGoal() must hold).
  [[nodiscard]] const TaskGoal& goal() const { return goals_[goal_]; }
  [[nodiscard]] const std::vector<TaskGoal>& goals() const { return goals_; }

 private:
  /// The stage the task is in while driving to, or dwelling at, goal `index`.
  [[nodiscard]] TaskState stageFor(std::size_t index, bool dwelling) const;
  [[nodiscard]] float progress() const;
  /// The current goal from 1 (0 without goals).
  [[nodiscard]] std::uint32_t step() const;
  void reportStage(TaskState st, std::int64_t nowNs);
  /// A leg towards the current goal begins: Driving; reports EnRoute / Delivering if that changed.
  void leg(std::int64_t nowNs);

  std::string task_;
  std::uint32_t revision_ = 0;
  std::int32_t priority_ = 0;
  bool paused_ = false;
  std::vector<TaskGoal> goals_;
  std::size_t goal_ = 0;
  Phase phase_ = Phase::Idle;
  std::int64_t phaseStartNs_ = 0;
  TaskState reported_ = TaskState::Queued;
  std::optional<TaskReport> pending_;
  std::vector<TaskReport> refusals_;  // orders refused, reported before the task's own (oldest first)
};

}  // namespace fleet::agent
