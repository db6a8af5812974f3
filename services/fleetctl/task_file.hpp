#pragma once

// Task files an operator submits: JSON (one task, an array, or {"tasks": [...]}) or CSV with a
// header row naming the columns (id,kind,pickup,dropoff,station,robot,priority,load_s,unload_s,
// deadline_ns,steps). Errors name the file, the line and the column.

#include <nlohmann/json.hpp>
#include <string>

#include "fleet/core/expected.hpp"

namespace fleet::ctl {

/// `text` without a leading UTF-8 byte-order mark (as Excel writes "CSV UTF-8").
std::string withoutBom(const std::string& text);

/// Parses CSV text (a leading byte-order mark is skipped) into the JSON array the HTTP API takes. Field types
/// are checked here; the semantics (stations, kinds) are the server's job.
Expected<nlohmann::json> csvToTasks(const std::string& text, const std::string& origin);

/// A multi-stop task's steps as written in a CSV cell: `;`-separated steps, each
/// `action:station[:load_id[:seconds]]` (`pick:P-1:L-42;drop:D-2:L-42;wait:::5;goto:X;charge:C-1`).
/// Empty parts are left out; the steps' meaning is the server's to check.
Expected<nlohmann::json> stepsFromText(const std::string& text);

/// Reads a .json or .csv file into a JSON array of task objects.
Expected<nlohmann::json> loadTaskFile(const std::string& path);

}  // namespace fleet::ctl
