#pragma once

// The one TaskState of the project: the fleet's state machine (libs/fleet task_state.hpp: which
// transitions are allowed), the wire (IDL TaskState, libs/messages: the same enum under msg::) and
// the API's names all use it. Pure: no DDS, no logging.

#include <array>
#include <cstddef>
#include <cstdint>
#include <string_view>

namespace fleet {

/// Life of a task. Transport tasks go queued → assigned → en_route → loading → delivering →
/// unloading → done; go-to, charge and park tasks go queued → assigned → en_route → done.
/// Any non-terminal state may end in failed or cancelled; an active task (assigned … unloading)
/// may be requeued (its robot was lost or it failed with attempts left), and a requeued task is
/// assigned again (directly or after going back to queued). `Rejected` is no state of a stored
/// task: the answer to a submission that was refused (TaskAck.state, the API's outcome). The order
/// is the IDL's (TS_QUEUED ... TS_REJECTED).
enum class TaskState : std::uint8_t {
  Queued,
  Assigned,
  EnRoute,
  Loading,
  Delivering,
  Unloading,
  Done,
  Failed,
  Cancelled,
  Requeued,
  Rejected
};

/// The wire and API names, in the enum's order.
inline constexpr std::array<std::string_view, 11> kTaskStateNames = {
    "queued", "assigned", "en_route",  "loading",  "delivering", "unloading",
    "done",   "failed",   "cancelled", "requeued", "rejected"};

/// "queued", "assigned", "en_route", ..., "rejected".
inline constexpr std::string_view taskStateName(TaskState s) {
  return kTaskStateNames.at(static_cast<std::size_t>(s));
}

}  // namespace fleet
