// fleetctl: the operator's command line. Talks to the WMS adapter's HTTP API.
//   fleetctl submit tasks.csv        submit tasks from a JSON or CSV file
//   fleetctl tasks [--state S]       list tasks          fleetctl task ID     one task
//   fleetctl cancel ID               cancel a task       fleetctl robots      list robots
//   fleetctl pause ID | resume ID    hold a task (its robot stands still) / let it go on
//   fleetctl change ID [--priority N] [--deadline T | --deadline-ns N | --no-deadline]  a waiting task
//   fleetctl follow [--count N] [--since ID]  print task events as they happen (after event ID)
//   fleetctl health | metrics
//   fleetctl loadtest [--robots N --humans M | --scenario F] [--fault ...]   run a whole fleet
//   fleetctl traffic-bench --map F.map --agents N --steps T   the lifelong planner alone on a grid
//   fleetctl vda5050-files DIR --robots r3,r4 --map-id M   broker, ACL and bridge files for vehicles

// Each subcommand, with its options and its work, is in a cmd_*.cpp of its own (commands.hpp).

#include <CLI/CLI.hpp>

#include "commands.hpp"
#include "fleet/service/command_line.hpp"

int main(int argc, char** argv) {
  CLI::App app{"fleetctl: operate the warehouse fleet through the WMS adapter"};
  app.require_subcommand(1);
  fleet::service::addVersion(app);
  fleet::ctl::Commands commands;
  fleet::ctl::addApiCommands(app, commands);
  fleet::ctl::addLoadtestCommand(app, commands);
  fleet::ctl::addSiteCommand(app, commands);
  fleet::ctl::addTrafficBenchCommand(app, commands);
  fleet::ctl::addTrafficSimCommand(app, commands);
  fleet::ctl::addVda5050FilesCommand(app, commands);
  // Exit codes as every binary's: 0 after --help/--version, 2 for any usage error.
  if (auto code = fleet::service::parse(app, argc, argv)) {
    return *code;
  }
  for (const auto& command : commands) {
    if (*command.app) {
      return command.run();
    }
  }
  return 0;
}
