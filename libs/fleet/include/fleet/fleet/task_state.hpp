#pragma once

#include <array>
#include <optional>
#include <string_view>

#include "fleet/core/expected.hpp"
#include "fleet/core/task_state.hpp"

namespace fleet {

/// Multistop: the task is its steps (task.hpp TaskStep), visited in order.
enum class TaskKind { Transport, Goto, Charge, Park, Multistop };

/// The states a stored task can be in (every TaskState but Rejected, the answer to a refused
/// submission), in the enum's order.
inline constexpr std::array<TaskState, 10> kAllTaskStates = {
    TaskState::Queued,     TaskState::Assigned,  TaskState::EnRoute, TaskState::Loading,
    TaskState::Delivering, TaskState::Unloading, TaskState::Done,    TaskState::Failed,
    TaskState::Cancelled,  TaskState::Requeued};
inline constexpr std::array<TaskKind, 5> kAllTaskKinds = {
    TaskKind::Transport, TaskKind::Goto, TaskKind::Charge, TaskKind::Park, TaskKind::Multistop};

/// Wire names: "queued", "assigned", "en_route", "loading", "delivering", "unloading", "done",
/// "failed", "cancelled", "requeued".
std::string_view toString(TaskState s);
std::optional<TaskState> parseTaskState(std::string_view name);
/// Wire names: "transport", "goto", "charge", "park", "multistop".
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
