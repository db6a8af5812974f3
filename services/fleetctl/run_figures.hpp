#pragma once

// The run's figures beyond task accounting, added to loadtest.json: "fleet_bound"
// (run_fleet_bound.hpp), "robot_time" and "stations" (run_ledger.hpp, over the simulator's replay).

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace fleet::ctl {

/// Adds the three blocks to `report` (each {"error": why} when it cannot be made; a wall-clock run
/// has no fleet bound rate of its own clock but its ledgers are made all the same). Never throws.
void addRunFigures(nlohmann::json& report, const std::filesystem::path& runDir, bool wallClock);

/// The lines the run prints for them.
std::vector<std::string> runFigureLines(const nlohmann::json& report);

}  // namespace fleet::ctl
