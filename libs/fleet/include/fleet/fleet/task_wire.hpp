#pragma once

// A task on the wire: the WMS adapter sends it, the fleet manager reads it, through this one pair
// of conversions (the Task topic carries the typed fields only).

#include <cstdint>
#include <string>

#include "fleet/fleet/task.hpp"
#include "fleet/messages/messages.hpp"

namespace fleet {

/// The request for `t` (its created time, or `nowNs` when the client left it out).
msg::Task toWire(const Task& t, std::string requestId, std::int64_t nowNs);
/// The task a request carries, as received at `nowNs` (unvalidated: the dispatcher checks it).
Task fromWire(const msg::Task& m, std::int64_t nowNs);

}  // namespace fleet
