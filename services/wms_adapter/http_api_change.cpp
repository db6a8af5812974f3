// PATCH /v1/tasks/{id}: a waiting task's priority and deadline changed (task_change_request.hpp
// reads the body; the fleet manager decides, docs/algorithms.md "Changing a queued task").

#include "http_api.hpp"
#include "json_reply.hpp"
#include "task_change_request.hpp"

namespace fleet::wms {

using nlohmann::json;

void HttpApi::patchTask(const Request& req, Response& res) {
  const std::string id = req.matches[1];
  auto parsed = parseTaskChange(id, req.body);
  if (auto* errors = std::get_if<std::vector<FieldError>>(&parsed)) {
    res.audit = json{{"task", id}, {"action", "change"}}.dump();
    json fields = json::array();
    for (const auto& f : *errors) {
      fields.push_back({{"path", f.path}, {"reason", f.reason}});
    }
    replyJson(res, 400, {{"error", "invalid"}, {"message", "the task was not changed"}, {"fields", fields}});
    return;
  }
  auto& m = std::get<msg::Task>(parsed);
  json audit = {{"task", id}, {"action", "change"}};
  if (m.set_priority) {
    audit["priority"] = m.priority;
  }
  if (m.set_deadline) {
    audit["deadline_ns"] = m.deadline_ns;
  }
  res.audit = audit.dump();
  if (!admitTaskRequest(id, "changed", res)) {
    return;
  }
  m.request_id = nextRequestId();
  const auto acks = gateway_.submit({m}, std::chrono::milliseconds(settings_.ackTimeoutMs));
  const auto& a = acks[0];
  if (!a) {
    res.set_header("Retry-After", "2");
    replyJson(res, 503,
              {{"error", "unavailable"},
               {"message", "the fleet manager did not acknowledge in time; retry (a change is idempotent)"}});
    return;
  }
  switch (a->result) {
    case msg::AckResult::Stored:
      replyJson(res, 200, taskChangedJson(*a));
      return;
    case msg::AckResult::NotFound:
      replyJson(res, 404, {{"error", "not_found"}, {"message", "no task with id \"" + id + "\""}});
      return;
    case msg::AckResult::Refused:
      // Assigned, on its way or finished: the message and `state` name where it stands.
      replyJson(res, 409,
                {{"error", "conflict"}, {"message", a->detail}, {"state", msg::toString(a->state)}});
      return;
    case msg::AckResult::Invalid: {
      json fields = json::parse(a->detail, nullptr, false);
      if (!fields.is_array()) {
        fields = json::array({{{"path", ""}, {"reason", a->detail}}});
      }
      replyJson(res, 400,
                {{"error", "invalid"}, {"message", "the task was not changed"}, {"fields", fields}});
      return;
    }
    default:
      res.set_header("Retry-After", "2");
      replyJson(res, 503, {{"error", "unavailable"}, {"message", a->detail}});
      return;
  }
}

}  // namespace fleet::wms
