#pragma once

// The TaskAck answers the fleet manager builds (fleet_manager_node.cpp, fleet_manager_control.cpp).

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "fleet/core/expected.hpp"
#include "fleet/fleet/errors.hpp"
#include "fleet/fleet/task.hpp"
#include "fleet/messages/messages.hpp"

namespace fleet::manager::acks {

/// The answer to `req`; `detail` cut to the field's 1023 characters.
inline msg::TaskAck ack(const msg::Task& req, msg::AckResult r, msg::TaskState state, std::string detail,
                        std::int64_t nowNs) {
  if (detail.size() > 1023) {
    detail = detail.substr(0, 1020) + "...";
  }
  return {req.request_id, req.task_id, r, state, std::move(detail), nowNs};
}

/// An operator request (cancel, pause, resume, change) on an unknown or finished task.
inline msg::TaskAck refused(const msg::Task& req, const Error& e, std::int64_t nowNs,
                            msg::TaskState state = msg::TaskState::Rejected) {
  return ack(req, e.code == errc::kNotFound ? msg::AckResult::NotFound : msg::AckResult::Refused, state,
             e.message, nowNs);
}

/// Field errors as the ack's detail of ACK_INVALID: [{"path": …, "reason": …}, …].
inline std::string fieldsJson(const std::vector<FieldError>& fields) {
  nlohmann::json a = nlohmann::json::array();
  for (const auto& f : fields) {
    a.push_back({{"path", f.path}, {"reason", f.reason}});
  }
  return a.dump();
}

}  // namespace fleet::manager::acks
