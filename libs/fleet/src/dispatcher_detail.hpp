#pragma once

// What the dispatcher's files share about a task: the states it passes through and the stations it
// occupies.

#include <algorithm>
#include <string>
#include <string_view>
#include <tuple>
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

/// Oldest first (pinned and urgent before that), so a busy station's queue is served in order.
inline void oldestFirst(std::vector<Task>& waiting) {
  std::stable_sort(waiting.begin(), waiting.end(), [](const Task& a, const Task& b) {
    return std::tuple(a.robot.empty(), -a.priority, a.createdNs) <
           std::tuple(b.robot.empty(), -b.priority, b.createdNs);
  });
}

/// What a task's wait reason says when a station's line had no place for it (noteAdmissionWaits).
inline constexpr std::string_view kPlaceInLine = " for a place in station ";

}  // namespace fleet::dispatcher_detail
