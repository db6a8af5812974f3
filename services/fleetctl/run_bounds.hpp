#pragma once

// The kinematic-bound figures of a finished load-test run, from what the run leaves in its folder:
// the fleet manager's task database (each done task's last assignment: robot and simulated time),
// the simulator's replay (every robot's pose at every step: where that robot was then), and the
// scenario the agents ran (stations, each robot's disc and limits: its cruise, as the agent takes
// it). The computation itself is kinematic_bound.hpp.

#include <cstddef>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

namespace fleet::ctl {

/// `loadtest.json`'s "kinematic_bound" block: per done task its bound and task time (last
/// assignment → first done), tasks without a bound with the reason, and the mean task time against
/// the mean bound (boundFigures). On a folder it cannot read it returns {"error": why}; it never
/// throws. The fleet's rate is stated against the fleet bound (run_fleet_bound.hpp).
nlohmann::json runBounds(const std::filesystem::path& runDir);

/// That block as the line the run prints.
std::string boundLine(const nlohmann::json& block);

}  // namespace fleet::ctl
