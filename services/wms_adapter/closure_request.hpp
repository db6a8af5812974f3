#pragma once

// Roadmap closures over the HTTP API (PUT/DELETE/GET /v1/traffic/closures): the request body as
// a TrafficClosure for the traffic manager, and a closure as the API shows it. Pure: no DDS.

#include <cstddef>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "fleet/fleet/task.hpp"
#include "fleet/messages/messages.hpp"

namespace fleet::wms {

/// The body of PUT /v1/traffic/closures/{id}: {"area": [[x, y], ...], "nodes": [id, ...],
/// "lanes": [[from, to], ...], "reason": "..."}, at least one of area, nodes and lanes. Every field
/// that is wrong is named (path and reason); node ids are checked against `roadmapNodes` when the
/// roadmap is known. `id` must be a valid id (the route's).
std::variant<msg::TrafficClosure, std::vector<FieldError>> parseClosure(
    const std::string& id, const std::string& body, std::optional<std::size_t> roadmapNodes,
    std::int64_t nowNs);

/// A closure as GET shows it (the body's form plus id and stamp).
nlohmann::json closureJson(const msg::TrafficClosure& c);

}  // namespace fleet::wms
