#pragma once

// The load test's first stage: the run's scenario. A scenario file is taken as is (its task list
// checked), or one is generated for the fleet size from a template, its map and stations written
// to the run folder as the run's site. The later stages read what this one finds (stations,
// robots, the site and its extent); every problem is reported here, before any process starts.

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "fault_plan.hpp"
#include "fleet/core/expected.hpp"
#include "loadtest.hpp"
#include "scenario_tasks.hpp"

namespace fleet::ctl {

struct RunScenario {
  nlohmann::json scenario;              // as the run uses it (the site's stations in site_stations)
  std::filesystem::path file;           // the run folder's scenario.json (without site_stations)
  std::vector<ScenarioTask> listTasks;  // the scenario's task list, by at_s (stable)
  bool fromList = false;                // post the list (else tasks are generated)
  std::vector<std::string> pickups, dropoffs, robots;
  std::string siteFile;            // the site every service reads
  double widthM = 0, heightM = 0;  // the map's extent (the site's when there is one)
};

/// Reads or generates the scenario and writes it (and a generated site) to `out`. Errors name the
/// file and what is wrong: unreadable JSON, a bad task list or site, no pickup or drop-off station,
/// no site (the traffic manager needs one for its roadmap).
Expected<RunScenario> prepareScenario(const LoadtestOptions& o, const std::filesystem::path& out);

/// A fault plan the run cannot carry out: a stall of a robot the scenario lacks, a kill of an
/// agent process beyond --agents.
Expected<void> checkFaults(const std::vector<Fault>& faults, const RunScenario& run, int agents);

/// Tasks per simulated minute: the option, 0.75 per robot, or the task list's average rate.
double taskRatePerMin(const LoadtestOptions& o, const RunScenario& run, int listTarget);

}  // namespace fleet::ctl
