#pragma once
// fleetctl's subcommands. Each add-function declares one subcommand (or a family of them) on the
// app, with its options, and registers what it does once the command line is parsed; main builds
// the app, calls them all, parses and runs the one given.

#include <CLI/CLI.hpp>
#include <functional>
#include <vector>

namespace fleet::ctl {

// A subcommand and its work: run() is called after parsing when `*app` was given; it returns the
// exit code.
struct Command {
  CLI::App* app = nullptr;
  std::function<int()> run;
};
using Commands = std::vector<Command>;

// The WMS adapter's HTTP API: the options --url, --ca-cert and --token-file, and the subcommands
// submit, tasks, task, change, cancel, pause, resume, robots, close, reopen, closures, follow, health and
// metrics (cmd_api.cpp).
void addApiCommands(CLI::App& app, Commands& commands);
// loadtest: a whole fleet here, fed tasks, faults injected, a report (cmd_loadtest.cpp).
void addLoadtestCommand(CLI::App& app, Commands& commands);
// site check: validate a site or map file (cmd_site.cpp).
void addSiteCommand(CLI::App& app, Commands& commands);
// traffic-bench: the lifelong planner alone on a MovingAI grid (cmd_traffic_bench.cpp).
void addTrafficBenchCommand(CLI::App& app, Commands& commands);
// traffic-sim: the traffic layer driving a virtual fleet on a site (cmd_traffic_sim.cpp).
void addTrafficSimCommand(CLI::App& app, Commands& commands);
// vda5050-files: broker, ACL and bridge files for VDA 5050 vehicles (cmd_vda5050_files.cpp).
void addVda5050FilesCommand(CLI::App& app, Commands& commands);

}  // namespace fleet::ctl
