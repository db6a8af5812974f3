// fleetctl loadtest: start a whole fleet here, feed it tasks, inject faults, report.

#include <memory>

#include "commands.hpp"
#include "loadtest.hpp"

namespace fleet::ctl {

void addLoadtestCommand(CLI::App& app, Commands& commands) {
  auto* loadtest =
      app.add_subcommand("loadtest", "start a whole fleet here, feed it tasks, inject faults, report");
  auto o = std::make_shared<LoadtestOptions>();
  o->templ = FLEETCTL_SOURCE_DIR "/sim/scenarios/small_warehouse.json";
  o->reportScript = FLEETCTL_SOURCE_DIR "/scripts/report.py";
  o->securityScript = FLEETCTL_SOURCE_DIR "/scripts/dds-security";
  o->binDir = FLEETCTL_BINARY_DIR;
  o->out = "reports/loadtest";
  loadtest->add_option("--scenario", o->scenario, "run this scenario file as is (else one is generated)");
  loadtest->add_option("--template", o->templ, "template of generated scenarios")->capture_default_str();
  loadtest->add_option("--robots", o->robots, "robots of the generated scenario")
      ->check(CLI::Range(1, 2000))
      ->capture_default_str();
  loadtest
      ->add_option("--site-for", o->siteRobots,
                   "size the generated warehouse (floor, parking, stations) for this many robots and place "
                   "--robots of "
                   "them: fleet sizes compared on one site (0: sized for --robots)")
      ->check(CLI::Range(0, 2000));
  loadtest->add_option("--humans", o->humans, "humans of the generated scenario")
      ->check(CLI::Range(0, 5000))
      ->capture_default_str();
  // Tasks: the scenario's `tasks` list when it has one, unless --rate, --tasks or --generate-tasks.
  auto* rateOpt = loadtest
                      ->add_option("--rate", o->ratePerMin,
                                   "generate this many tasks per simulated minute (0 = 0.75 per robot)")
                      ->check(CLI::Range(0.0, 100000.0));
  auto* tasksOpt =
      loadtest->add_option("--tasks", o->maxTasks, "generate at most this many tasks (0 = no cap)")
          ->check(CLI::Range(0, 1000000));
  loadtest->add_flag("--generate-tasks", o->generateTasks,
                     "generate tasks even if the scenario has a task list (implied by --rate and --tasks)");
  loadtest->add_flag("--until-done", o->untilDone,
                     "with --tasks or a task list: stop as soon as every task is done, failed or cancelled");
  loadtest
      ->add_option("--station-load", o->stationLoad,
                   "how a task loads its stations: task (pickup and drop-off for the whole task) or phase "
                   "(the pickup until loaded, the drop-off for the whole task) or arrival (each from the "
                   "robot's predicted "
                   "arrival there until served)")
      ->check(CLI::IsMember({"task", "phase", "arrival"}))
      ->capture_default_str();
  loadtest
      ->add_option(
          "--let-pass", o->letPass,
          "reserved traffic: route nodes a robot must be short of a conflict before one waiting on it "
          "there may go first (switchable dependencies); 0: never (default: the traffic manager's)")
      ->check(CLI::Range(0, 1000));
  loadtest
      ->add_option("--guidance", o->guidance,
                   "reserved traffic: the roadmap's flow guidance (roadmap.guidance of the traffic and fleet "
                   "managers; 0: none; default: theirs)")
      ->check(CLI::Range(0.0, 100.0));
  loadtest
      ->add_option("--core", o->core,
                   "reserved traffic: the traffic manager's planner core, pibt (lifelong PIBT, one step at a "
                   "time) or sipp (windowed prioritized planning over safe intervals; default: the traffic "
                   "manager's)")
      ->check(CLI::IsMember({"pibt", "sipp"}));
  loadtest
      ->add_option("--yield-after", o->yieldAfterS,
                   "reserved traffic: seconds a robot reports itself blocked (a person in front of it) "
                   "before it is made to yield; 0: never (default: the traffic manager's)")
      ->check(CLI::Range(0.0, 3600.0));
  loadtest
      ->add_option("--station-capacity", o->stationCapacity,
                   "active tasks per station (0 = no limit), or queue: as many as the station's line on the "
                   "roadmap holds (its dock and queue nodes)")
      ->check(CLI::IsMember({"queue"}) | CLI::Range(0, 1000))
      ->capture_default_str();
  loadtest
      ->add_option("--travel-cost", o->travelCost,
                   "fleet manager's travel costs: along paths on the map, straight lines, or free-flow times "
                   "on the roadmap (needs the scenario's site)")
      ->check(CLI::IsMember({"path", "straight", "roadmap"}))
      ->capture_default_str();
  loadtest
      ->add_option("--return-home", o->returnHomeS, "idle seconds before a robot drives home (< 0: never)")
      ->capture_default_str();
  loadtest->add_option("--dds-security", o->ddsSecurity,
                       "run every process with its DDS Security identity from this folder (made by "
                       "scripts/dds-security deployment DIR; each agent process gets an identity of its "
                       "own for its robots, made in the folder for the run)");
  loadtest->add_option("--duration", o->durationS, "simulated seconds")
      ->check(CLI::Range(1.0, 86400.0))
      ->capture_default_str();
  loadtest->add_option("--wall-limit", o->wallLimitS, "stop after this many wall seconds whatever happens")
      ->check(CLI::Range(5.0, 86400.0))
      ->capture_default_str();
  loadtest->add_option("--agents", o->agents, "robot agent processes")
      ->check(CLI::Range(1, 64))
      ->capture_default_str();
  loadtest->add_option("--fault", o->faults,
                       "kill-agent@T[+D][:K], kill-manager@T[+D], kill-traffic@T[+D], stall:ROBOT@T+D, "
                       "drop-dds=F (T simulated s, "
                       "D wall s), "
                       "hide-landmarks@T+D, close@T+D:X1,Y1,X2,Y2,X3,Y3,... (T and D simulated s)");
  loadtest->add_option("--out", o->out, "run folder (report, logs, database)")->capture_default_str();
  loadtest->add_option("--bin", o->binDir, "build tree with the services")->capture_default_str();
  loadtest->add_option("--report-script", o->reportScript, "scripts/report.py ('' = no HTML report)");
  loadtest->add_option("--port", o->port, "WMS adapter port (0 = a free one)");
  loadtest->add_option("--domain", o->domain, "DDS domain (default FLEET_DDS_DOMAIN or a random one)")
      ->check(CLI::Range(0, 229));
  loadtest->add_option("--seed", o->seed, "scenario and task seed")->capture_default_str();
  loadtest->add_option("--local-planner", o->localPlanner, "robot agents' local planner")
      ->capture_default_str();
  loadtest
      ->add_option(
          "--agent-config", o->agentConfig,
          "robot agents' --config: JSON with local_planner, dwa {...}, safety {...} (see robot_agent --help)")
      ->check(CLI::ExistingFile);
  loadtest
      ->add_option("--max-speed", o->maxSpeed,
                   "at most this many simulated s per wall s (0 = as fast as the fleet steps)")
      ->check(CLI::Range(0.0, 1000.0));
  loadtest->add_option("--step-timeout-ms", o->stepTimeoutMs, "lockstep step timeout of the simulator")
      ->check(CLI::Range(10, 60000))
      ->capture_default_str();
  loadtest
      ->add_option(
          "--vda5050", o->vda5050,
          "the last N robots are VDA 5050 vehicles (simulated, over a Mosquitto broker of the run's own, "
          "behind vda5050_bridge)")
      ->check(CLI::NonNegativeNumber);
  loadtest->add_flag("--wall-clock", o->wallClock,
                     "run every service on the wall clock at 1x, as in production (default: lockstep); "
                     "reports the robot agents' achieved control rate");
  loadtest
      ->add_option("--store", o->store,
                   "the fleet manager's task store: sqlite (one manager) or postgresql (a PostgreSQL server "
                   "of the run's own in the run folder, on a Unix socket, and two managers on it: "
                   "kill-manager kills the active one and the standby takes over)")
      ->check(CLI::IsMember({"sqlite", "postgresql"}))
      ->capture_default_str();
  loadtest->add_flag("--serve", o->serve,
                     "after the run, keep the dashboard up on its final state and serve the report (with "
                     "its replay) on 127.0.0.1 until Ctrl-C");
  commands.push_back({loadtest, [o, rateOpt, tasksOpt] {
                        o->generateTasks = o->generateTasks || rateOpt->count() > 0 || tasksOpt->count() > 0;
                        return runLoadtest(*o);
                      }});
}

}  // namespace fleet::ctl
