#pragma once

// `fleetctl loadtest`: starts the whole fleet on this machine under a Supervisor, feeds tasks over
// the WMS adapter's HTTP API (the scenario's task list, each at its simulated time, or generated at
// a given arrival rate in simulated time), injects faults, prints
// progress, stops everything, reconciles acknowledged tasks with the manager's database and writes
// loadtest.json (plus the HTML report through scripts/report.py).

#include <string>
#include <vector>

namespace fleet::ctl {

struct LoadtestOptions {
  std::string scenario;  // a scenario file to run as is; empty: generate one
  std::string templ;     // template for generated scenarios
  int robots = 20;       // generated scenarios
  int siteRobots = 0;    // generated scenarios: size the site for this many robots (0: robots)
  int humans = 8;
  double ratePerMin = 0;   // tasks per simulated minute; 0: 0.75 per robot
  int maxTasks = 0;        // 0: no cap besides the duration
  bool untilDone = false;  // with maxTasks or a task list: stop once every task is done/failed/cancelled
  /// Generate tasks at ratePerMin even if the scenario has a `tasks` list (set by --generate-tasks
  /// and whenever --rate or --tasks is given); else the list, when there is one, is posted as is.
  bool generateTasks = false;
  double durationS = 180;   // simulated seconds
  double wallLimitS = 600;  // the run is stopped after this much wall time whatever happens
  int agents = 1;           // robot agent processes (besides one per stalled robot)
  std::vector<std::string> faults;
  std::string out;           // run folder
  std::string binDir;        // build tree holding the services
  std::string reportScript;  // scripts/report.py; empty: no HTML report
  int port = 0;              // 0: a free port
  int domain = -1;           // -1: FLEET_DDS_DOMAIN or a random one
  std::uint64_t seed = 7;
  std::string localPlanner = "dwa";
  std::string agentConfig;    // robot agents' --config (a JSON file; empty: none)
  int letPass = -1;           // the traffic manager's let_pass (route nodes; 0 off); -1: its default
  double guidance = -1.0;     // roadmap.guidance of the traffic and fleet managers; <0: their default
  std::string core;           // the traffic manager's planner core (pibt or sipp); empty: its default
  double yieldAfterS = -1.0;  // the traffic manager's yield_after_s (0 off); < 0: its default
  /// The fleet manager's station_load (task or phase) and station_capacity (active tasks per
  /// station, "0": no limit, or "queue": as many as the station's line on the roadmap holds, dock
  /// and queue nodes). Default: admission by slots — a task is admitted when its pickup and its
  /// drop-off each have a place in their line, its pickup counted until it has loaded, its drop-off
  /// for the whole task (docs/algorithms.md, "Traffic: stations as servers").
  std::string stationLoad = "phase";
  std::string stationCapacity = "queue";
  std::string travelCost = "path";  // the fleet manager's travel_cost (path | straight | roadmap)
  double returnHomeS = 5.0;         // robot agents' --return-home (negative: stay where a task ends)
  /// A folder made by scripts/dds-security ("deployment DIR"): every process joins with its
  /// identity (fleet-manager, wms-adapter, risk-map, traffic-manager, simulator). Each agent
  /// process (and the VDA 5050 bridge) gets an identity of its own made for the run with
  /// `securityScript`, granting only its robots' partitions ("agent-0" ...; needs DIR/ca.key).
  /// Empty: no DDS Security.
  std::string ddsSecurity;
  std::string securityScript;  // scripts/dds-security
  int stepTimeoutMs = 300;
  /// Every service on the wall clock, as in production: the simulator runs at 1x, robot agents
  /// at their configured rate (their achieved rate is reported), and nothing waits for anyone.
  bool wallClock = false;
  /// Cap on simulated seconds per wall second (0: none). The fleet manager, WMS adapter and load
  /// generator run on the wall clock; uncapped, a fast machine compresses their latencies into
  /// long simulated ones.
  double maxSpeed = 4.0;
  double progressEveryS = 2.0;
  /// The last N robots of the scenario run as VDA 5050 vehicles (fleet-sim --vda5050) behind a
  /// vda5050_bridge and a Mosquitto broker of the run's own; needs reserved traffic.
  int vda5050 = 0;
  /// After a run that ended normally, keep the WMS adapter up (the dashboard on the run's final
  /// state) and serve the report with its replay on another loopback port, until Ctrl-C.
  bool serve = false;
  /// The fleet manager's task store: "sqlite" (one manager, the run folder's fleet.db) or
  /// "postgresql" (a PostgreSQL server of the run's own and two managers on it, one standing by;
  /// kill-manager kills the active one and the report times the takeover).
  std::string store = "sqlite";
};

/// Runs the load test; returns the process exit code (0 ok, 3 lost or duplicated tasks, 1 error,
/// 130 interrupted).
int runLoadtest(const LoadtestOptions& o);

}  // namespace fleet::ctl
