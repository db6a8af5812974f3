// fleetctl traffic-sim: the traffic layer driving a virtual fleet on a site (no simulator).

#include <map>
#include <memory>
#include <string>

#include "commands.hpp"
#include "traffic_sim.hpp"

namespace fleet::ctl {

void addTrafficSimCommand(CLI::App& app, Commands& commands) {
  auto* trafficSim = app.add_subcommand(
      "traffic-sim",
      "the traffic layer driving a virtual fleet on a site (no simulator): tasks/h, stalls, safety");
  auto o = std::make_shared<TrafficSimOptions>();
  trafficSim->add_option("--site", o->site, "site.json")->required();
  trafficSim->add_option("--robots", o->robots, "robots")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  trafficSim->add_option("--duration", o->duration, "simulated seconds")
      ->check(CLI::Range(1.0, 1e7))
      ->capture_default_str();
  trafficSim->add_option("--seeds", o->seeds, "a seed or a range, e.g. 1-8")->capture_default_str();
  trafficSim
      ->add_option("--core", o->core,
                   "the traffic layer's planner: pibt (lifelong PIBT, one step at a time) or sipp (windowed "
                   "prioritized planning over safe intervals)")
      ->capture_default_str();
  trafficSim->add_option("--spacing", o->spacing, "roadmap lattice spacing in m (0: default)")
      ->check(CLI::Range(0.0, 10.0));
  trafficSim->add_option("--stop-chance", o->stopChance, "per edge: chance a robot stops on it up to 10 s")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  trafficSim
      ->add_option(
          "--turn-scale", o->turnScale,
          "factor on the virtual robots' time to turn on the spot; the plans keep the modelled turn time "
          "(1: as modelled, 0: instant turns, to measure what turning costs the fleet)")
      ->check(CLI::Range(0.0, 10.0))
      ->capture_default_str();
  trafficSim
      ->add_option("--guidance", o->guidance,
                   "flow guidance: driving against the usual flow between pickups and drop-offs costs routes "
                   "1 + this times the edge's time (0: none; default: the roadmap's)")
      ->check(CLI::Range(0.0, 100.0));
  trafficSim
      ->add_option("--stop-gap", o->stopGap,
                   "m of free space the robot's motion gate needs ahead of a driving robot (default: the "
                   "roadmap's)")
      ->check(CLI::Range(0.0, 5.0));
  trafficSim
      ->add_option("--let-pass", o->letPass,
                   "route nodes a robot must be short of a conflict before a robot waiting on it there may "
                   "go first (switchable dependencies); 0: never (default: the traffic layer's)")
      ->check(CLI::Range(0, 1000));
  trafficSim
      ->add_option("--max-lag", o->maxLag,
                   "lattice edges' time (0.7 s each) a robot may fall behind the plan before everyone's "
                   "unreleased plan is dropped and planned again (default: the traffic layer's)")
      ->check(CLI::Range(1, 100000));
  trafficSim
      ->add_option("--prefer-straight", o->straight,
                   "1: among equally short moves the planner takes the one that turns least; 0: at random "
                   "(default: the traffic layer's)")
      ->check(CLI::Range(0, 1));
  trafficSim
      ->add_option("--detour-after", o->detourAfter,
                   "planner steps a robot stands short of its goal before it is routed round "
                   "robots standing in its way (0: never; default: the traffic layer's)")
      ->check(CLI::Range(0, 100000));
  trafficSim
      ->add_option("--detour-penalty", o->detourPenalty,
                   "s added to a route for entering what a standing robot excludes (default: the "
                   "traffic layer's)")
      ->check(CLI::Range(0.0, 1e6));
  trafficSim
      ->add_option("--occupied-cost", o->occupiedCost,
                   "s the planner adds to a move into what a standing robot excludes, which would push "
                   "it (0: plain PIBT; default: the traffic layer's)")
      ->check(CLI::Range(0.0, 600.0));
  trafficSim
      ->add_option("--queue-length", o->queueLength,
                   "queue nodes generated for a station the site gives none (default: the roadmap's)")
      ->check(CLI::Range(0, 50));
  trafficSim
      ->add_option(
          "--station-lines", o->stationLines,
          "1: robots sent to a station wait in line on its queue nodes; 0: all are planned to the dock")
      ->check(CLI::Range(0, 1))
      ->capture_default_str();
  trafficSim
      ->add_option(
          "--admission", o->admission,
          "slots: a task is given only when its pickup and drop-off each have a free place in their "
          "line (its places scaled by the admission governor, as in the fleet manager; --station-slots is a "
          "fixed cap), a robot "
          "counting from its task until served; arrival: a place for the time the robot "
          "will get there; a robot with no admissible task waits at a parking place; none: every task at "
          "once (0, 1, 2 name them too)")
      ->transform(CLI::CheckedTransformer(
          std::map<std::string, int>{{"none", 0}, {"slots", 1}, {"arrival", 2}}, CLI::ignore_case))
      ->capture_default_str();
  trafficSim
      ->add_option("--station-slots", o->stationSlots,
                   "slots per station for admission (0: its line, the dock and its queue places)")
      ->check(CLI::Range(0, 1000))
      ->capture_default_str();
  trafficSim
      ->add_option("--stations", o->stations,
                   "tasks only between these pickups and drop-offs, comma-separated names (default: all)")
      ->delimiter(',');
  trafficSim->add_flag("--json", o->json, "print the results as JSON");
  trafficSim->add_option(
      "--html", o->html,
      "write a replay page of the first seed's run (roadmap, robots, releases) to this file");
  commands.push_back({trafficSim, [o] { return runTrafficSim(*o); }});
}

}  // namespace fleet::ctl
