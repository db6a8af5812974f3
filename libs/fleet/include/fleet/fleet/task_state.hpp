#pragma once

#include <array>
#include <optional>
#include <string_view>

#include "fleet/core/expected.hpp"

namespace fleet {

enum class TaskKind { Transport, Goto, Charge, Park };

/// Life of a task. Transport tasks go queued → assigned → en_route → loading → delivering →
/// unloading → done; go-to, charge and park tasks go queued → assigned → en_route → done.
/// Any non-terminal state may end in failed or cancelled; an active task (assigned … unloading)
/// may be requeued (its robot was lost or it failed with attempts left), and a requeued task is
/// assigned again (directly or after going back to queued).
enum class TaskState {
  Queued,
  Assigned,
  EnRoute,
  Loading,
  Delivering,
  Unloading,
  Done,
  Failed,
  Cancelled,
  Requeued
};

inline constexpr std::array<TaskState, 10> kAllTaskStates = {
    TaskState::Queued,     TaskState::Assigned,  TaskState::EnRoute, TaskState::Loading,
    TaskState::Delivering, TaskState::Unloading, TaskState::Done,    TaskState::Failed,
    TaskState::Cancelled,  TaskState::Requeued};
inline constexpr std::array<TaskKind, 4> kAllTaskKinds = {TaskKind::Transport, TaskKind::Goto,
                                                          TaskKind::Charge, TaskKind::Park};

/// Wire names: "queued", "assigned", "en_route", "loading", "delivering", "unloading", "done",
/// "failed", "cancelled", "requeued".
std::string_view toString(TaskState s);
std::optional<TaskState> parseTaskState(std::string_view name);
/// Wire names: "transport", "goto", "charge", "park".
std::string_view toString(TaskKind k);
std::optional<TaskKind> parseTaskKind(std::string_view name);

/// done, failed, cancelled: nothing may follow.
bool isTerminal(TaskState s);
/// assigned … unloading: a robot holds the task.
bool isActive(TaskState s);
/// queued or requeued: waiting for a robot.
bool isWaiting(TaskState s);

/// Whether `from → to` is legal for some task kind. Error code "illegal_transition".
Expected<void> checkTransition(TaskState from, TaskState to);
/// Whether `from → to` is legal for a task of `kind` (only transport tasks load and unload; only
/// the others go from en_route straight to done).
Expected<void> checkTransition(TaskState from, TaskState to, TaskKind kind);

}  // namespace fleet
