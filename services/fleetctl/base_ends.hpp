#pragma once

// Where the robots met the end of what the traffic manager had released to them, from its summary
// (traffic_manager_summary.json, written when it stops). A robot that reaches its base's last node
// short of its target brakes there; the traffic manager says why the base ended there: `held` (a
// robot planned before it on the next node had not left: a stop the plan asks for), `plan_end`
// (the planner had not planned it further yet) or `limit` (more was free: a longer base came too
// late, the release latency). The target is 0 stops of a vehicle on time, i.e. none but `held`;
// The load test splits the counts between robot agents and VDA 5050 vehicles.

#include <set>
#include <string>

#include <nlohmann/json.hpp>

namespace fleet::ctl {

/// The traffic manager's summary with `base_ends_agents` and `base_ends_vehicles` added (each
/// {held, plan_end, limit}); `vehicles` are the robot ids of the VDA 5050 vehicles.
[[nodiscard]] nlohmann::json trafficSummaryJson(const nlohmann::json& summary,
                                                const std::set<std::string>& vehicles);

/// "base ends reached short of the target: agents 40 held, 2 at the plan's end, 0 late; ...".
[[nodiscard]] std::string baseEndsLine(const nlohmann::json& traffic);

}  // namespace fleet::ctl
