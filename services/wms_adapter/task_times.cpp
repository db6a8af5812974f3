#include "task_times.hpp"

#include "rfc3339.hpp"

namespace fleet::wms {
namespace {

constexpr const char* kTimes[][2] = {{"deadline", "deadline_ns"}, {"created", "created_ns"}};

void acceptOne(nlohmann::json& task, const std::string& prefix, std::vector<FieldError>& out) {
  if (!task.is_object()) {
    return;  // parseTasks names it
  }
  for (const auto& [text, ns] : kTimes) {
    if (!task.contains(text)) {
      continue;
    }
    const std::string path = prefix.empty() ? text : prefix + "." + text;
    const auto& v = task[text];
    std::string why;
    const auto parsed = v.is_string() ? parseRfc3339(v.get<std::string>(), &why) : std::nullopt;
    if (!parsed) {
      out.push_back({path, v.is_string() ? why : "expected an RFC 3339 time as a string"});
      continue;
    }
    if (task.contains(ns) && !(task[ns].is_number_integer() && task[ns].get<std::int64_t>() == *parsed)) {
      out.push_back({path, std::string("differs from ") + ns + " (give one of the two)"});
      continue;
    }
    task[ns] = *parsed;
    task.erase(text);
  }
}

}  // namespace

std::vector<FieldError> acceptTaskTimes(nlohmann::json& body) {
  std::vector<FieldError> out;
  if (body.is_array()) {
    for (std::size_t i = 0; i < body.size(); ++i) {
      acceptOne(body[i], "[" + std::to_string(i) + "]", out);
    }
  } else if (body.is_object() && body.contains("tasks") && !body.contains("id")) {
    if (body["tasks"].is_array()) {
      for (std::size_t i = 0; i < body["tasks"].size(); ++i) {
        acceptOne(body["tasks"][i], "tasks[" + std::to_string(i) + "]", out);
      }
    }
  } else {
    acceptOne(body, "", out);
  }
  return out;
}

void showTaskTimes(nlohmann::json& task) {
  if (!task.is_object()) {
    return;
  }
  for (const auto& [text, ns] : kTimes) {
    if (task.contains(ns) && task[ns].is_number_integer() && task[ns].get<std::int64_t>() > 0) {
      task[text] = toRfc3339(task[ns].get<std::int64_t>());
    }
  }
}

}  // namespace fleet::wms
