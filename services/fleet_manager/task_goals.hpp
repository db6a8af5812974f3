#pragma once

// The goals of a robot's order for a task: where it drives, in order, and what it does at each
// stop. No DDS: the node puts them in a TaskAssignment.

#include <string>
#include <vector>

#include "fleet/core/expected.hpp"
#include "fleet/fleet/station_map.hpp"
#include "fleet/fleet/task.hpp"
#include "fleet/messages/messages.hpp"

namespace fleet::manager {

/// Transport: pickup (load) then drop-off (unload). Goto, charge, park: the station (a charge goal
/// dwells at most `chargeMaxS`; the manager ends the task once charged). Multistop: one goal a
/// step (pick: load, drop: unload, with the load id; charge: charge for the step's duration or
/// `chargeMaxS`; wait: no action, the duration, at its station or the stop before). Error
/// "internal" naming a station that is not on the site, or a task with no stop at all.
Expected<std::vector<msg::Goal>> taskGoals(const Task& t, const StationMap& stations, double chargeMaxS);

}  // namespace fleet::manager
