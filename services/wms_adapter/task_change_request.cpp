#include "task_change_request.hpp"

#include <limits>

#include "fleet/core/bounded_json.hpp"
#include "fleet/core/ids.hpp"
#include "task_times.hpp"

namespace fleet::wms {

using nlohmann::json;

std::variant<msg::Task, std::vector<FieldError>> parseTaskChange(const std::string& id,
                                                                 const std::string& body) {
  std::vector<FieldError> errors;
  if (!isValidId(id)) {
    errors.push_back({"id", "not a valid task id"});
  }
  // Two numbers and a time: bounded before parsing.
  auto parsed = parseBoundedJson(body, {.maxBytes = 64 * 1024, .maxDepth = 4, .maxElements = 64});
  if (!parsed) {
    errors.push_back({"", "the body is not acceptable JSON: " + parsed.error().message});
    return errors;
  }
  if (!parsed->is_object()) {
    errors.push_back({"", "the body must be a JSON object"});
    return errors;
  }
  json& j = *parsed;
  for (const auto& [key, value] : j.items()) {
    if (key != "priority" && key != "deadline" && key != "deadline_ns") {
      errors.push_back({key, "unknown field (a change sets priority, deadline or deadline_ns)"});
    }
  }
  // "deadline" as RFC 3339 becomes deadline_ns, as in a submission.
  for (auto& e : acceptTaskTimes(j)) {
    errors.push_back(std::move(e));
  }
  msg::Task m;
  m.task_id = id;
  m.control = msg::TaskControl::Change;
  if (auto it = j.find("priority"); it != j.end()) {
    if (!it->is_number_integer()) {
      errors.push_back({"priority", "expected an integer"});
    } else if (it->is_number_unsigned()
                   ? it->get<std::uint64_t>() > static_cast<std::uint64_t>(kMaxPriority)
                   : (it->get<std::int64_t>() < kMinPriority || it->get<std::int64_t>() > kMaxPriority)) {
      errors.push_back({"priority", "must be in [" + std::to_string(kMinPriority) + ", " +
                                        std::to_string(kMaxPriority) + "]"});
    } else {
      m.priority = static_cast<std::int32_t>(it->get<std::int64_t>());
      m.set_priority = true;
    }
  }
  if (auto it = j.find("deadline_ns"); it != j.end()) {
    if (!it->is_number_integer() ||
        (it->is_number_unsigned() &&
         it->get<std::uint64_t>() > static_cast<std::uint64_t>(std::numeric_limits<std::int64_t>::max()))) {
      errors.push_back({"deadline_ns", "expected an integer of ns (0 = no deadline)"});
    } else if (it->get<std::int64_t>() < 0) {
      errors.push_back({"deadline_ns", "must be >= 0 (0 = no deadline)"});
    } else {
      m.deadline_ns = it->get<std::int64_t>();
      m.set_deadline = true;
    }
  }
  const bool named = j.contains("priority") || j.contains("deadline_ns") || j.contains("deadline");
  if (!named) {
    errors.push_back({"", "give priority, deadline (RFC 3339) or deadline_ns, or several"});
  }
  if (!errors.empty()) {
    return errors;
  }
  return m;
}

json taskChangedJson(const msg::TaskAck& a) {
  const json d = json::parse(a.detail, nullptr, false);
  json out = {{"id", a.task_id}, {"state", msg::toString(a.state)}};
  if (d.is_object()) {
    out["priority"] = d.value("priority", 0);
    out["deadline_ns"] = d.value("deadline_ns", std::int64_t{0});
    out["changed"] = d.value("changed", false);
  }
  showTaskTimes(out);
  out.erase("created");  // a task's times: only the deadline here
  return out;
}

}  // namespace fleet::wms
