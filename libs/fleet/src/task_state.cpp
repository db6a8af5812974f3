#include "fleet/fleet/task_state.hpp"

#include <string>

#include "fleet/fleet/errors.hpp"

namespace fleet {
namespace {

constexpr std::array<std::string_view, 5> kKindNames = {"transport", "goto", "charge", "park", "multistop"};

// Which step follows which on the happy path; failure, cancellation and requeue are added below.
bool forwardStep(TaskState from, TaskState to) {
  using S = TaskState;
  switch (from) {
    case S::Queued:
      return to == S::Assigned;
    case S::Requeued:
      return to == S::Queued || to == S::Assigned;
    case S::Assigned:
      return to == S::EnRoute;
    case S::EnRoute:
      return to == S::Loading || to == S::Done;
    case S::Loading:
      return to == S::Delivering;
    case S::Delivering:
      return to == S::Unloading;
    case S::Unloading:
      return to == S::Done;
    default:
      return false;
  }
}

}  // namespace

std::string_view toString(TaskState s) {
  return taskStateName(s);
}

std::optional<TaskState> parseTaskState(std::string_view name) {
  for (const auto s : kAllTaskStates) {
    if (taskStateName(s) == name) {
      return s;
    }
  }
  return std::nullopt;
}

std::string_view toString(TaskKind k) {
  return kKindNames.at(static_cast<std::size_t>(k));
}

std::optional<TaskKind> parseTaskKind(std::string_view name) {
  for (std::size_t i = 0; i < kKindNames.size(); ++i) {
    if (kKindNames[i] == name) {
      return static_cast<TaskKind>(i);
    }
  }
  return std::nullopt;
}

bool isTerminal(TaskState s) {
  return s == TaskState::Done || s == TaskState::Failed || s == TaskState::Cancelled;
}

bool isActive(TaskState s) {
  return s == TaskState::Assigned || s == TaskState::EnRoute || s == TaskState::Loading ||
         s == TaskState::Delivering || s == TaskState::Unloading;
}

bool isWaiting(TaskState s) {
  return s == TaskState::Queued || s == TaskState::Requeued;
}

Expected<void> checkTransition(TaskState from, TaskState to) {
  bool ok = false;
  if (!isTerminal(from) && from != TaskState::Rejected) {  // a refused submission has no life after it
    ok = forwardStep(from, to) || to == TaskState::Failed || to == TaskState::Cancelled ||
         (to == TaskState::Requeued && isActive(from));
  }
  if (!ok) {
    return unexpected(errc::kIllegalTransition, "illegal transition " + std::string(toString(from)) + " -> " +
                                                    std::string(toString(to)));
  }
  return {};
}

Expected<void> checkTransition(TaskState from, TaskState to, TaskKind kind) {
  auto base = checkTransition(from, to);
  if (!base) {
    return base;
  }
  if (from == TaskState::EnRoute) {
    const bool transport = kind == TaskKind::Transport;
    if ((to == TaskState::Loading && !transport) || (to == TaskState::Done && transport)) {
      return unexpected(errc::kIllegalTransition, "illegal transition " + std::string(toString(from)) +
                                                      " -> " + std::string(toString(to)) + " for a " +
                                                      std::string(toString(kind)) + " task");
    }
  }
  return {};
}

}  // namespace fleet
