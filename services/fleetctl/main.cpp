// fleetctl: the operator's command line. Talks to the WMS adapter's HTTP API.
//   fleetctl submit tasks.csv        submit tasks from a JSON or CSV file
//   fleetctl tasks [--state S]       list tasks          fleetctl task ID     one task
//   fleetctl cancel ID               cancel a task       fleetctl robots      list robots
//   fleetctl pause ID | resume ID    hold a task (its robot stands still) / let it go on
//   fleetctl follow [--count N]      print task events as they happen
//   fleetctl health | metrics
//   fleetctl loadtest [--robots N --humans M | --scenario F] [--fault ...]   run a whole fleet
//   fleetctl traffic-bench --map F.map --agents N --steps T   the lifelong planner alone on a grid
//   fleetctl vda5050-files DIR --robots r3,r4 --map-id M   broker, ACL and bridge files for vehicles

#include <httplib.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <cstdlib>
#include <iostream>

#include "fleet/core/bounded_file.hpp"
#include "fleet/service/command_line.hpp"
#include "loadtest.hpp"
#include "site_check.hpp"
#include "task_file.hpp"
#include "traffic_bench.hpp"
#include "traffic_sim.hpp"
#include "url.hpp"
#include "vda5050_setup.hpp"

using nlohmann::json;

namespace {

struct Target {
  fleet::ctl::Url url;
  std::string token;
};

httplib::Headers headers(const Target& t) {
  if (t.token.empty()) {
    return {};
  }
  return {{"Authorization", "Bearer " + t.token}};
}

int fail(const std::string& msg) {
  std::fprintf(stderr, "fleetctl: %s\n", msg.c_str());
  return 1;
}

int show(const httplib::Result& r) {
  if (!r) {
    return fail("cannot reach the WMS adapter (" + httplib::to_string(r.error()) + ")");
  }
  auto j = json::parse(r->body, nullptr, false);
  std::cout << (j.is_discarded() ? r->body : j.dump(2)) << "\n";
  return r->status < 300 ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"fleetctl: operate the warehouse fleet through the WMS adapter"};
  app.require_subcommand(1);
  fleet::service::addVersion(app);
  std::string url = "http://127.0.0.1:8080";
  std::string tokenFile;
  app.add_option("--url", url, "WMS adapter address, http[s]://HOST[:PORT]")->envname("FLEET_WMS_URL");
  std::string caCert;
  app.add_option("--ca-cert", caCert,
                 "https: PEM file of the CA that signed the adapter's certificate (else the system's)")
      ->envname("FLEET_WMS_CA_CERT");
  app.add_option("--token-file", tokenFile, "file holding the bearer token (else FLEET_WMS_TOKEN)");

  auto* submit = app.add_subcommand("submit", "submit tasks from a JSON or CSV file");
  std::string file;
  int batch = 500;
  submit->add_option("file", file, "tasks.json or tasks.csv")->required();
  submit->add_option("--batch", batch, "tasks per request")->check(CLI::Range(1, 1000));
  auto* tasks = app.add_subcommand("tasks", "list tasks");
  std::string state;
  int limit = 100;
  tasks->add_option("--state", state, "queued, assigned, en_route, ..., done, failed, cancelled");
  tasks->add_option("--limit", limit)->check(CLI::Range(1, 100000));
  auto* task = app.add_subcommand("task", "show one task");
  std::string id;
  task->add_option("id", id)->required();
  auto* cancel = app.add_subcommand("cancel", "cancel a task");
  cancel->add_option("id", id)->required();
  auto* pause = app.add_subcommand(
      "pause", "hold a task: its robot stands still with it, a waiting task is not dispatched");
  pause->add_option("id", id)->required();
  auto* resume = app.add_subcommand("resume", "let a paused task go on");
  resume->add_option("id", id)->required();
  auto* robots = app.add_subcommand("robots", "list robots");
  auto* close = app.add_subcommand(
      "close", "close part of the roadmap to traffic (an area, nodes or lanes): robots are planned round it");
  close->add_option("id", id, "closure id (closing again under it replaces the closure)")->required();
  std::vector<double> closeArea;
  std::vector<int> closeNodes;
  std::vector<std::string> closeLanes;
  std::string closeReason;
  close->add_option("--area", closeArea, "polygon corners X1,Y1,X2,Y2,X3,Y3,... (m, map frame)")
      ->delimiter(',');
  close->add_option("--nodes", closeNodes, "roadmap node ids N1,N2,...")->delimiter(',');
  close->add_option("--lane", closeLanes,
                    "a directed roadmap edge FROM:TO (repeat; give both ways for both)");
  close->add_option("--reason", closeReason, "why (shown with the closure and in the traffic manager's log)");
  auto* reopen = app.add_subcommand("reopen", "reopen a closure");
  reopen->add_option("id", id)->required();
  auto* closures = app.add_subcommand("closures", "list the roadmap closures in force");
  auto* follow = app.add_subcommand("follow", "print task events as they happen");
  int count = 0;
  int seconds = 0;
  follow->add_option("--count", count, "stop after this many events (0 = never)");
  follow->add_option("--seconds", seconds, "stop after this long (0 = never)");
  auto* health = app.add_subcommand("health", "is the adapter up and does it see the manager");
  auto* metrics = app.add_subcommand("metrics", "the adapter's counters");
  auto* loadtest =
      app.add_subcommand("loadtest", "start a whole fleet here, feed it tasks, inject faults, report");
  fleet::ctl::LoadtestOptions lt;
  lt.templ = FLEETCTL_SOURCE_DIR "/sim/scenarios/small_warehouse.json";
  lt.reportScript = FLEETCTL_SOURCE_DIR "/scripts/report.py";
  lt.securityScript = FLEETCTL_SOURCE_DIR "/scripts/dds-security";
  lt.binDir = FLEETCTL_BINARY_DIR;
  lt.out = "reports/loadtest";
  loadtest->add_option("--scenario", lt.scenario, "run this scenario file as is (else one is generated)");
  loadtest->add_option("--template", lt.templ, "template of generated scenarios")->capture_default_str();
  loadtest->add_option("--robots", lt.robots, "robots of the generated scenario")
      ->check(CLI::Range(1, 2000))
      ->capture_default_str();
  loadtest
      ->add_option("--site-for", lt.siteRobots,
                   "size the generated warehouse (floor, parking, stations) for this many robots and place "
                   "--robots of "
                   "them: fleet sizes compared on one site (0: sized for --robots)")
      ->check(CLI::Range(0, 2000));
  loadtest->add_option("--humans", lt.humans, "humans of the generated scenario")
      ->check(CLI::Range(0, 5000))
      ->capture_default_str();
  // Tasks: the scenario's `tasks` list when it has one, unless --rate, --tasks or --generate-tasks.
  auto* rateOpt = loadtest
                      ->add_option("--rate", lt.ratePerMin,
                                   "generate this many tasks per simulated minute (0 = 0.75 per robot)")
                      ->check(CLI::Range(0.0, 100000.0));
  auto* tasksOpt =
      loadtest->add_option("--tasks", lt.maxTasks, "generate at most this many tasks (0 = no cap)")
          ->check(CLI::Range(0, 1000000));
  loadtest->add_flag("--generate-tasks", lt.generateTasks,
                     "generate tasks even if the scenario has a task list (implied by --rate and --tasks)");
  loadtest->add_flag("--until-done", lt.untilDone,
                     "with --tasks or a task list: stop as soon as every task is done, failed or cancelled");
  loadtest
      ->add_option("--station-load", lt.stationLoad,
                   "how a task loads its stations: task (pickup and drop-off for the whole task) or phase "
                   "(the pickup until loaded, then the drop-off)")
      ->check(CLI::IsMember({"task", "phase"}))
      ->capture_default_str();
  loadtest
      ->add_option(
          "--let-pass", lt.letPass,
          "reserved traffic: route nodes a robot must be short of a conflict before one waiting on it "
          "there may go first (switchable dependencies); 0: never (default: the traffic manager's)")
      ->check(CLI::Range(0, 1000));
  loadtest
      ->add_option("--yield-after", lt.yieldAfterS,
                   "reserved traffic: seconds a robot reports itself blocked (a person in front of it) "
                   "before it is made to yield; 0: never (default: the traffic manager's)")
      ->check(CLI::Range(0.0, 3600.0));
  loadtest
      ->add_option("--station-capacity", lt.stationCapacity,
                   "active tasks per station (0 = no limit), or queue: as many as the station's line on the "
                   "roadmap holds (its dock and queue nodes)")
      ->check(CLI::IsMember({"queue"}) | CLI::Range(0, 1000))
      ->capture_default_str();
  loadtest
      ->add_option("--travel-cost", lt.travelCost,
                   "fleet manager's travel costs: along paths on the map, straight lines, or free-flow times "
                   "on the roadmap (needs the scenario's site)")
      ->check(CLI::IsMember({"path", "straight", "roadmap"}))
      ->capture_default_str();
  loadtest
      ->add_option("--return-home", lt.returnHomeS, "idle seconds before a robot drives home (< 0: never)")
      ->capture_default_str();
  loadtest->add_option("--dds-security", lt.ddsSecurity,
                       "run every process with its DDS Security identity from this folder (made by "
                       "scripts/dds-security deployment DIR; each agent process gets an identity of its "
                       "own for its robots, made in the folder for the run)");
  loadtest->add_option("--duration", lt.durationS, "simulated seconds")
      ->check(CLI::Range(1.0, 86400.0))
      ->capture_default_str();
  loadtest->add_option("--wall-limit", lt.wallLimitS, "stop after this many wall seconds whatever happens")
      ->check(CLI::Range(5.0, 86400.0))
      ->capture_default_str();
  loadtest->add_option("--agents", lt.agents, "robot agent processes")
      ->check(CLI::Range(1, 64))
      ->capture_default_str();
  loadtest->add_option("--fault", lt.faults,
                       "kill-agent@T[+D][:K], kill-manager@T[+D], kill-traffic@T[+D], stall:ROBOT@T+D, "
                       "drop-dds=F (T simulated s, "
                       "D wall s), "
                       "hide-landmarks@T+D, close@T+D:X1,Y1,X2,Y2,X3,Y3,... (T and D simulated s)");
  loadtest->add_option("--out", lt.out, "run folder (report, logs, database)")->capture_default_str();
  loadtest->add_option("--bin", lt.binDir, "build tree with the services")->capture_default_str();
  loadtest->add_option("--report-script", lt.reportScript, "scripts/report.py ('' = no HTML report)");
  loadtest->add_option("--port", lt.port, "WMS adapter port (0 = a free one)");
  loadtest->add_option("--domain", lt.domain, "DDS domain (default FLEET_DDS_DOMAIN or a random one)")
      ->check(CLI::Range(0, 229));
  loadtest->add_option("--seed", lt.seed, "scenario and task seed")->capture_default_str();
  loadtest->add_option("--local-planner", lt.localPlanner, "robot agents' local planner")
      ->capture_default_str();
  loadtest
      ->add_option(
          "--agent-config", lt.agentConfig,
          "robot agents' --config: JSON with local_planner, dwa {...}, safety {...} (see robot_agent --help)")
      ->check(CLI::ExistingFile);
  loadtest
      ->add_option("--max-speed", lt.maxSpeed,
                   "at most this many simulated s per wall s (0 = as fast as the fleet steps)")
      ->check(CLI::Range(0.0, 1000.0));
  loadtest->add_option("--step-timeout-ms", lt.stepTimeoutMs, "lockstep step timeout of the simulator")
      ->check(CLI::Range(10, 60000))
      ->capture_default_str();
  loadtest
      ->add_option(
          "--vda5050", lt.vda5050,
          "the last N robots are VDA 5050 vehicles (simulated, over a Mosquitto broker of the run's own, "
          "behind vda5050_bridge)")
      ->check(CLI::NonNegativeNumber);
  loadtest->add_flag("--wall-clock", lt.wallClock,
                     "run every service on the wall clock at 1x, as in production (default: lockstep); "
                     "reports the robot agents' achieved control rate");
  loadtest->add_flag("--serve", lt.serve,
                     "after the run, keep the dashboard up on its final state and serve the report (with "
                     "its replay) on 127.0.0.1 until Ctrl-C");
  auto* site = app.add_subcommand("site", "site files");
  auto* siteCheck = site->add_subcommand("check", "validate a site or map file and print what it holds");
  std::string siteFile;
  double siteRadius = 0.0;
  double mapResolution = 1.0;
  bool siteJson = false;
  siteCheck
      ->add_option("file", siteFile, "site.json, a scenario naming a site, MovingAI .map or ROS map .yaml")
      ->required();
  siteCheck->add_option("--radius", siteRadius, "robot radius in m (default: the site's robot)")
      ->check(CLI::Range(0.0, 10.0));
  siteCheck->add_option("--resolution", mapResolution, "m per cell of a MovingAI .map")
      ->check(CLI::Range(1e-3, 100.0))
      ->capture_default_str();
  siteCheck->add_flag("--json", siteJson, "print the report as JSON");
  std::string siteSvg;
  siteCheck->add_option("--svg", siteSvg, "draw the map, the roadmap and the stations into this SVG file");
  site->require_subcommand(1);
  auto* trafficBench = app.add_subcommand(
      "traffic-bench",
      "the lifelong multi-agent planner alone on a MovingAI grid: throughput, planning time, the plan");
  fleet::ctl::TrafficBenchOptions tb;
  bool noRotationPass = false;
  trafficBench->add_option("--map", tb.map, "MovingAI .map file")->required();
  trafficBench->add_option("--scen", tb.scen,
                           "MovingAI .scen of the same map: agents start (and first head) where its rows say "
                           "(bad rows skipped and counted on stderr)");
  trafficBench->add_option("--agents", tb.agents, "agents")->capture_default_str();
  trafficBench->add_option("--steps", tb.steps, "steps (lifelong mode)")->capture_default_str();
  trafficBench->add_option("--seed", tb.seed, "seed of starts, goals, tasks and the planner")
      ->capture_default_str();
  trafficBench->add_option("--out", tb.out,
                           "write the plan (every step, every agent's cell, the goals) as JSON");
  trafficBench->add_flag("--no-rotation-pass", noRotationPass,
                         "allow rotations (cycles of agents each following the next), as pibt2 does");
  trafficBench->add_option("--rotations", tb.rotations, "avoid | cancel | allow")->capture_default_str();
  trafficBench
      ->add_option("--escape-after", tb.escapeAfter,
                   "steps without coming closer to its goal before an agent is escalated (0: plain PIBT)")
      ->capture_default_str();
  trafficBench
      ->add_option("--escape-progress", tb.escapeProgress,
                   "cells an escalated agent gains on where it was escalated before it drops back")
      ->capture_default_str();
  trafficBench->add_flag("--mapd", tb.mapd,
                         "pickup and delivery (pibt2's MAPD setting) instead of lifelong MAPF");
  trafficBench->add_option("--pd", tb.pd,
                           "pibt2 .pd file: pickup, delivery and endpoint cells (with --mapd)");
  trafficBench->add_option("--tasks", tb.tasks, "MAPD: tasks in all")->capture_default_str();
  trafficBench->add_option("--frequency", tb.frequency, "MAPD: new tasks per step")->capture_default_str();
  trafficBench->add_option("--max-steps", tb.maxSteps, "MAPD: give up after this many steps")
      ->capture_default_str();
  auto* trafficSim = app.add_subcommand(
      "traffic-sim",
      "the traffic layer driving a virtual fleet on a site (no simulator): tasks/h, stalls, safety");
  fleet::ctl::TrafficSimOptions ts;
  trafficSim->add_option("--site", ts.site, "site.json")->required();
  trafficSim->add_option("--robots", ts.robots, "robots")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  trafficSim->add_option("--duration", ts.duration, "simulated seconds")
      ->check(CLI::Range(1.0, 1e7))
      ->capture_default_str();
  trafficSim->add_option("--seeds", ts.seeds, "a seed or a range, e.g. 1-8")->capture_default_str();
  trafficSim->add_option("--spacing", ts.spacing, "roadmap lattice spacing in m (0: default)")
      ->check(CLI::Range(0.0, 10.0));
  trafficSim->add_option("--stop-chance", ts.stopChance, "per edge: chance a robot stops on it up to 10 s")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  trafficSim
      ->add_option("--stop-gap", ts.stopGap,
                   "m of free space the robot's motion gate needs ahead of a driving robot (default: the "
                   "roadmap's)")
      ->check(CLI::Range(0.0, 5.0));
  trafficSim
      ->add_option("--let-pass", ts.letPass,
                   "route nodes a robot must be short of a conflict before a robot waiting on it there may "
                   "go first (switchable dependencies); 0: never (default: the traffic layer's)")
      ->check(CLI::Range(0, 1000));
  trafficSim
      ->add_option("--max-lag", ts.maxLag,
                   "planner steps a robot may fall behind the plan before everyone's unreleased plan is "
                   "dropped and planned again (default: the traffic layer's)")
      ->check(CLI::Range(1, 100000));
  trafficSim
      ->add_option("--prefer-straight", ts.straight,
                   "1: among equally short moves the planner takes the one that turns least; 0: at random "
                   "(default: the traffic layer's)")
      ->check(CLI::Range(0, 1));
  trafficSim
      ->add_option("--detour-after", ts.detourAfter,
                   "planner steps a robot stands short of its goal before it is routed round "
                   "robots standing in its way (0: never; default: the traffic layer's)")
      ->check(CLI::Range(0, 100000));
  trafficSim
      ->add_option("--detour-penalty", ts.detourPenalty,
                   "s added to a route for entering what a standing robot excludes (default: the "
                   "traffic layer's)")
      ->check(CLI::Range(0.0, 1e6));
  trafficSim
      ->add_option("--queue-length", ts.queueLength,
                   "queue nodes generated for a station the site gives none (default: the roadmap's)")
      ->check(CLI::Range(0, 50));
  trafficSim
      ->add_option(
          "--station-lines", ts.stationLines,
          "1: robots sent to a station wait in line on its queue nodes; 0: all are planned to the dock")
      ->check(CLI::Range(0, 1))
      ->capture_default_str();
  trafficSim
      ->add_option(
          "--admission", ts.admission,
          "1: a task is given only when its pickup and drop-off each have a free slot (a place in "
          "their line); a robot with no admissible task waits at a parking place; 0: every task at once")
      ->check(CLI::Range(0, 1))
      ->capture_default_str();
  trafficSim
      ->add_option("--station-slots", ts.stationSlots,
                   "slots per station for admission (0: its line, the dock and its queue places)")
      ->check(CLI::Range(0, 1000))
      ->capture_default_str();
  trafficSim->add_flag("--json", ts.json, "print the results as JSON");
  trafficSim->add_option(
      "--html", ts.html,
      "write a replay page of the first seed's run (roadmap, robots, releases) to this file");
  auto* vdaFiles = app.add_subcommand(
      "vda5050-files",
      "write a Mosquitto configuration (listener, one password per vehicle, an ACL confining each to "
      "its topic subtree), the bridge's configuration and fleet-sim's vehicles file, e.g. for "
      "deploy/compose.vda5050.yaml");
  fleet::ctl::Vda5050Files vf;
  std::string vfRobots;
  std::string vfSeenAt;
  vdaFiles->add_option("dir", vf.out, "directory to write into (created)")->required();
  vdaFiles->add_option("--robots", vfRobots, "robot ids that are VDA 5050 vehicles, comma-separated")
      ->required();
  vdaFiles->add_option("--map-id", vf.map_id, "the VDA 5050 mapId (the site's name)")->required();
  vdaFiles
      ->add_option("--broker-host", vf.broker_host,
                   "the broker's address as the bridge and vehicles reach it")
      ->capture_default_str();
  vdaFiles->add_option("--bind", vf.bind_address, "the broker's listening address")->capture_default_str();
  vdaFiles->add_option("--port", vf.port, "the broker's port")->required()->check(CLI::Range(1, 65535));
  vdaFiles->add_option("--seen-at", vfSeenAt,
                       "the directory's path as the broker reads it (e.g. its mount point in a container); "
                       "the broker then logs to stderr");
  vdaFiles->add_flag("!--wall-clock", vf.sim_clock, "the bridge on the wall clock (default: lockstep)");
  // Exit codes as every binary's: 0 after --help/--version, 2 for any usage error.
  if (auto code = fleet::service::parse(app, argc, argv)) {
    return *code;
  }
  if (*trafficBench) {
    if (noRotationPass) {
      tb.rotations = "allow";
    }
    return fleet::ctl::runTrafficBench(tb);
  }
  if (*trafficSim) {
    return fleet::ctl::runTrafficSim(ts);
  }
  if (*vdaFiles) {
    for (std::size_t at = 0; at <= vfRobots.size();) {
      const std::size_t comma = std::min(vfRobots.find(',', at), vfRobots.size());
      if (comma > at) {
        vf.robots.push_back(vfRobots.substr(at, comma - at));
      }
      at = comma + 1;
    }
    for (const auto& r : vf.robots) {
      if (r.find_first_of("/#+ ") != std::string::npos) {
        std::cerr
            << "fleetctl vda5050-files: robot id \"" << r
            << "\" cannot be a VDA 5050 serial number (no '/', '#', '+' or spaces in MQTT topic levels)\n";
        return 2;
      }
    }
    if (vf.robots.empty()) {
      std::cerr << "fleetctl vda5050-files: --robots names no robot\n";
      return 2;
    }
    if (!vfSeenAt.empty()) {
      vf.seen_at = vfSeenAt;
      vf.log_to_file = false;
    }
    std::error_code ec;
    std::filesystem::create_directories(vf.out, ec);
    if (auto written = fleet::ctl::writeVda5050Files(vf); !written) {
      std::cerr << "fleetctl vda5050-files: " << written.error().message << "\n";
      return 1;
    }
    std::cout << "fleetctl vda5050-files: " << vf.robots.size() << " vehicle(s) written to "
              << vf.out.string() << "\n";
    return 0;
  }
  if (*siteCheck) {
    return fleet::ctl::siteCheck(siteFile, siteRadius, mapResolution, siteJson, siteSvg);
  }
  if (*loadtest) {
    lt.generateTasks = lt.generateTasks || rateOpt->count() > 0 || tasksOpt->count() > 0;
    return fleet::ctl::runLoadtest(lt);
  }

  Target t;
  if (auto u = fleet::ctl::parseUrl(url)) {
    t.url = *u;
  } else {
    std::fprintf(stderr, "fleetctl: %s\n", u.error().message.c_str());
    return 2;
  }
  if (!tokenFile.empty()) {
    auto text = fleet::readBoundedFile(tokenFile, fleet::kTokenFileLimit, "token_file");
    if (!text) {
      return fail("cannot read a token: " + text.error().message);
    }
    t.token = text->substr(0, text->find('\n'));
    if (!t.token.empty() && t.token.back() == '\r') {
      t.token.pop_back();
    }
    if (t.token.empty()) {
      return fail("cannot read a token from " + tokenFile + ": the first line is empty");
    }
  } else if (const char* env = std::getenv("FLEET_WMS_TOKEN")) {
    t.token = env;
  }
  // https works when cpp-httplib is built with OpenSSL (Debian's is: CPPHTTPLIB_OPENSSL_SUPPORT).
  httplib::Client c(t.url.text());
  if (!caCert.empty()) {
    if (t.url.scheme != "https") {
      std::fprintf(stderr, "fleetctl: --ca-cert goes with an https:// --url\n");
      return 2;
    }
    c.set_ca_cert_path(caCert);
  }
  c.set_read_timeout(30, 0);
  const auto h = headers(t);

  if (*submit) {
    auto all = fleet::ctl::loadTaskFile(file);
    if (!all) {
      return fail(all.error().message);
    }
    int ok = 0;
    int bad = 0;
    for (std::size_t i = 0; i < all->size(); i += static_cast<std::size_t>(batch)) {
      json part = json::array();
      for (std::size_t k = i; k < std::min(all->size(), i + static_cast<std::size_t>(batch)); ++k) {
        part.push_back((*all)[k]);
      }
      auto r = c.Post("/v1/tasks", h, part.dump(), "application/json");
      if (!r) {
        return fail("cannot reach the WMS adapter at " + url + " (" + httplib::to_string(r.error()) + ")");
      }
      auto body = json::parse(r->body, nullptr, false);
      if (body.is_object() && body.contains("results")) {
        for (const auto& item : body["results"]) {
          const int s = item.value("status", 0);
          if (s == 200 || s == 201) {
            ++ok;
          } else {
            ++bad;
            std::cerr << "fleetctl: " << item.dump() << "\n";
          }
        }
      } else {
        bad += static_cast<int>(part.size());
        std::cerr << "fleetctl: HTTP " << r->status << ": " << r->body << "\n";
      }
    }
    std::printf("submitted %d tasks, %d refused\n", ok, bad);
    return bad == 0 ? 0 : 1;
  }
  if (*tasks) {
    std::string path = "/v1/tasks?limit=" + std::to_string(limit);
    if (!state.empty()) {
      path += "&state=" + state;
    }
    auto r = c.Get(path, h);
    if (!r || r->status != 200) {
      return show(r);
    }
    auto body = json::parse(r->body);
    std::printf("%-24s %-11s %-12s %s\n", "ID", "STATE", "ROBOT", "REASON");
    for (const auto& x : body["tasks"]) {
      std::printf("%-24s %-11s %-12s %s\n", x.value("id", "").c_str(), x.value("state", "").c_str(),
                  x.value("robot", "").c_str(), x.value("reason", "").c_str());
    }
    return 0;
  }
  if (*task) {
    return show(c.Get("/v1/tasks/" + id, h));
  }
  if (*cancel) {
    return show(c.Delete("/v1/tasks/" + id, h));
  }
  if (*pause || *resume) {
    return show(c.Post("/v1/tasks/" + id + (*pause ? "/pause" : "/resume"), h, "", "application/json"));
  }
  if (*close) {
    json body = json::object();
    if (!closeArea.empty()) {
      if (closeArea.size() % 2 != 0 || closeArea.size() < 6) {
        std::fprintf(stderr, "fleetctl close: --area takes X,Y pairs of at least 3 corners\n");
        return 2;
      }
      body["area"] = json::array();
      for (std::size_t i = 0; i + 1 < closeArea.size(); i += 2) {
        body["area"].push_back({closeArea[i], closeArea[i + 1]});
      }
    }
    if (!closeNodes.empty()) {
      body["nodes"] = closeNodes;
    }
    for (const auto& l : closeLanes) {
      const auto colon = l.find(':');
      int from = 0;
      int to = 0;
      if (colon == std::string::npos || std::sscanf(l.c_str(), "%d:%d", &from, &to) != 2) {
        std::fprintf(stderr, "fleetctl close: --lane \"%s\": expected FROM:TO (two node ids)\n", l.c_str());
        return 2;
      }
      body["lanes"].push_back({from, to});
    }
    if (!closeReason.empty()) {
      body["reason"] = closeReason;
    }
    return show(c.Put("/v1/traffic/closures/" + id, h, body.dump(), "application/json"));
  }
  if (*reopen) {
    return show(c.Delete("/v1/traffic/closures/" + id, h));
  }
  if (*closures) {
    return show(c.Get("/v1/traffic/closures", h));
  }
  if (*robots) {
    auto r = c.Get("/v1/robots", h);
    if (!r || r->status != 200) {
      return show(r);
    }
    std::printf("%-12s %8s %8s %7s %-9s %7s %s\n", "ID", "X", "Y", "THETA", "MODE", "BATTERY", "TASK");
    for (const auto& x : json::parse(r->body)["robots"]) {
      std::printf("%-12s %8.2f %8.2f %7.2f %-9s %6.0f%% %s\n", x.value("id", "").c_str(),
                  x["pose"].value("x", 0.0), x["pose"].value("y", 0.0), x["pose"].value("theta", 0.0),
                  x.value("mode", "").c_str(), 100.0 * x.value("battery", 0.0), x.value("task", "").c_str());
    }
    return 0;
  }
  if (*follow) {
    int seen = 0;
    const auto start = std::chrono::steady_clock::now();
    std::string buf;
    auto r = c.Get("/v1/events", h, [&](const char* data, std::size_t n) {
      buf.append(data, n);
      std::size_t pos = 0;
      while ((pos = buf.find("\n\n")) != std::string::npos) {
        const std::string frame = buf.substr(0, pos);
        buf.erase(0, pos + 2);
        const auto d = frame.find("data: ");
        if (d != std::string::npos) {
          std::cout << frame.substr(d + 6) << std::endl;
          ++seen;
        }
      }
      const bool timeUp =
          seconds > 0 && std::chrono::steady_clock::now() - start > std::chrono::seconds(seconds);
      return !(count > 0 && seen >= count) && !timeUp;
    });
    (void)r;
    return 0;
  }
  if (*health) {
    return show(c.Get("/v1/health", h));
  }
  if (*metrics) {
    return show(c.Get("/v1/metrics", h));
  }
  return 0;
}
