#pragma once

// A task's times as RFC 3339 text beside their ns (rfc3339.hpp): `deadline` for `deadline_ns` and
// `created` for `created_ns` are accepted in POST /v1/tasks and shown in every task the API returns
// (with `updated` for `updated_ns`).

#include <nlohmann/json.hpp>
#include <vector>

#include "fleet/fleet/task.hpp"

namespace fleet::wms {

/// Replaces, in each task of a POST /v1/tasks body (one task, an array, or {"tasks": [...]}), the
/// text `deadline` / `created` by `deadline_ns` / `created_ns`. Refused (named as parseTasks names
/// fields: "deadline", "[2].deadline", "tasks[2].deadline"): text that is not RFC 3339, or both forms
/// given with different values.
std::vector<FieldError> acceptTaskTimes(nlohmann::json& body);

/// Adds `deadline` and `created` (RFC 3339) beside a task JSON's non-zero `deadline_ns` / `created_ns`.
void showTaskTimes(nlohmann::json& task);

}  // namespace fleet::wms
