#pragma once

// A change of a waiting task's priority and deadline over the HTTP API (PATCH /v1/tasks/{id}):
// the request body as a TC_CHANGE request for the fleet manager, and the manager's answer as the
// API shows it. Pure: no DDS.

#include <nlohmann/json.hpp>
#include <string>
#include <variant>
#include <vector>

#include "fleet/fleet/task.hpp"
#include "fleet/messages/messages.hpp"

namespace fleet::wms {

/// The body of PATCH /v1/tasks/{id}: {"priority": int, "deadline": RFC 3339 | "deadline_ns": int},
/// at least one of priority and deadline; "deadline_ns": 0 takes the deadline away. Every field
/// that is wrong is named (path and reason): unknown fields, types, a priority outside
/// [kMinPriority, kMaxPriority], a negative deadline_ns, text that is not RFC 3339, deadline and
/// deadline_ns that disagree. `id` must be a valid id (the route's). The request has no request id.
std::variant<msg::Task, std::vector<FieldError>> parseTaskChange(const std::string& id,
                                                                 const std::string& body);

/// The answer to a change the manager stored: {"id", "state", "priority", "deadline_ns",
/// "deadline" (RFC 3339, beside a non-zero deadline_ns), "changed"} from the ack's detail.
nlohmann::json taskChangedJson(const msg::TaskAck& a);

}  // namespace fleet::wms
