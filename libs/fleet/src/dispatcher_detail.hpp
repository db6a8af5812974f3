#pragma once

// What the dispatcher's files share about a task: the states it passes through and the stations it
// occupies.

#include <string>
#include <vector>

#include "fleet/fleet/task.hpp"

namespace fleet::dispatcher_detail {

/// Happy path of a task kind, from assigned to done.
inline std::vector<TaskState> happyPath(TaskKind kind) {
  using S = TaskState;
  if (kind == TaskKind::Transport) {
    return {S::Assigned, S::EnRoute, S::Loading, S::Delivering, S::Unloading, S::Done};
  }
  return {S::Assigned, S::EnRoute, S::Done};
}

// The stations a task occupies while it is active: every stop, one entry a visit.
inline std::vector<const std::string*> stationsOf(const Task& t) {
  return taskStops(t);
}

}  // namespace fleet::dispatcher_detail
