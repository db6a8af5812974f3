#pragma once

// The load test's second stage: the fleet it starts. From the options, the run's scenario and the
// fault plan it writes each service's configuration into the run folder and returns every process
// to start, in dependency order, with the simulator apart (it starts last, once the WMS adapter
// answers): the fleet manager (two with --store postgresql), the WMS adapter, the risk map, the
// traffic manager, the robot agents (a process of their own for each stalled robot, the rest round
// robin over --agents) and, with --vda5050, a broker and the bridge. Nothing is started here.

#include <filesystem>
#include <map>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "fault_plan.hpp"
#include "fleet/core/expected.hpp"
#include "loadtest.hpp"
#include "loadtest_scenario.hpp"
#include "supervisor.hpp"

namespace fleet::ctl {

class StandbyManagers;

struct FleetPlan {
  int port = 0;                         // the WMS adapter's, on 127.0.0.1
  int domain = 0;                       // the DDS domain
  std::filesystem::path out;            // the run folder (logs, configuration)
  std::filesystem::path db;             // the manager's SQLite store
  std::vector<ProcessSpec> specs;       // in start order
  ProcessSpec manager;                  // the run's one manager (before --store postgresql's two)
  ProcessSpec sim;                      // the simulator, started last
  std::vector<std::string> agentNames;  // robot agent processes
  std::map<std::string, std::string> agentOfRobot;
  std::map<std::string, std::vector<std::string>> robotsOfProcess;  // DDS Security identities
  std::set<std::string> vdaRobots;                                  // run as VDA 5050 vehicles
  std::vector<std::string> warnings;                                // for the user, before the run starts
  [[nodiscard]] std::string logOf(const std::string& process) const;
};

/// A DDS domain no other run on this machine uses, held by a lock file for this process's life.
int lockFreeDomain();

/// A free TCP port on 127.0.0.1.
int freePort();

/// --dds-security: every fixed identity's folder and the CA's key are there, and no drop-dds fault
/// needs a CYCLONEDDS_URI of its own.
Expected<void> checkDdsSecurity(const LoadtestOptions& o, double dropFraction);

/// Writes the services' configuration files into `out` and returns the processes. `standby` (with
/// --store postgresql) gives the two managers; null: one manager on `out`/fleet.db.
Expected<FleetPlan> planFleet(const LoadtestOptions& o, const RunScenario& run,
                              const std::vector<Fault>& faults, const std::filesystem::path& out,
                              StandbyManagers* standby);

/// --dds-security: one identity per agent process (and the bridge) granting exactly its robots'
/// partitions, made with the security script.
Expected<void> makeIdentities(const LoadtestOptions& o, const FleetPlan& plan);

}  // namespace fleet::ctl
