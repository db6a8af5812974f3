#pragma once

// What the task document's files share: field paths and the station check (task.cpp), and the
// steps of a multi-stop task (task_steps.cpp).

#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <vector>

#include "fleet/fleet/station_map.hpp"
#include "fleet/fleet/task.hpp"

namespace fleet::task_detail {

/// `prefix.field`, or `field` without a prefix.
std::string join(std::string_view prefix, std::string_view field);

/// A valid id naming a station of the site (when `stations` is given) of kind `need`.
void checkStation(const std::string& name, std::string_view path, StationKind need,
                  const StationMap* stations, std::vector<FieldError>& out);

/// Reads `steps` (an array of step objects) into `t.steps`: types, unknown fields, actions. False
/// when a type was wrong (the semantic checks then say nothing more).
bool parseSteps(const nlohmann::json& steps, std::string_view prefix, Task& t, std::vector<FieldError>& out);

/// A multi-stop task's steps against the site: count, each step's station, load and duration, and
/// that every load dropped was picked before and every load picked is dropped.
void validateSteps(const Task& t, const StationMap* stations, std::string_view prefix,
                   std::vector<FieldError>& out);

/// The wire form of the steps (fields at their default value left out).
nlohmann::json stepsToJson(const std::vector<TaskStep>& steps);

}  // namespace fleet::task_detail
