#pragma once

// The fleet bound of a finished load-test run (fleet_bound.hpp), from its folder: the task list as
// the manager stored it (fleet.db, in posting order: each task's first transition) and the scenario
// the agents ran (site, robot starts, disc and cruise as the agent takes it).

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "fleet_bound.hpp"

namespace fleet::ctl {

/// `loadtest.json`'s "fleet_bound": the robot and station bounds, which binds, the measured rate
/// `fleetRatePerH` as a share of the bound, and per station its visits, share and least cycle.
/// {"error": why} on a folder it cannot read or a list it cannot bound; never throws.
nlohmann::json runFleetBound(const std::filesystem::path& runDir, double fleetRatePerH);

/// A FleetBound (and the measured rate) as that block; shared with `fleetctl traffic-sim`.
nlohmann::json fleetBoundJson(const FleetBound& b, double fleetRatePerH, double cruise, double radius);

/// The block as the line a run prints: "… tasks/h = x % of the fleet bound (robots | stations)".
std::string fleetBoundLine(const nlohmann::json& block);

}  // namespace fleet::ctl
