// fleetctl traffic-bench: the lifelong multi-agent planner alone on a MovingAI grid.

#include <memory>

#include "commands.hpp"
#include "traffic_bench.hpp"

namespace fleet::ctl {

namespace {

struct BenchCommandOptions {
  TrafficBenchOptions tb;
  bool noRotationPass = false;
};

}  // namespace

void addTrafficBenchCommand(CLI::App& app, Commands& commands) {
  auto* trafficBench = app.add_subcommand(
      "traffic-bench",
      "the lifelong multi-agent planner alone on a MovingAI grid: throughput, planning time, the plan");
  auto o = std::make_shared<BenchCommandOptions>();
  trafficBench->add_option("--map", o->tb.map, "MovingAI .map file")->required();
  trafficBench->add_option("--scen", o->tb.scen,
                           "MovingAI .scen of the same map: agents start (and first head) where its rows say "
                           "(bad rows skipped and counted on stderr)");
  trafficBench->add_option("--agents", o->tb.agents, "agents")->capture_default_str();
  trafficBench->add_option("--steps", o->tb.steps, "steps (lifelong mode)")->capture_default_str();
  trafficBench->add_option("--seed", o->tb.seed, "seed of starts, goals, tasks and the planner")
      ->capture_default_str();
  trafficBench->add_option("--out", o->tb.out,
                           "write the plan (every step, every agent's cell, the goals) as JSON");
  trafficBench->add_flag("--no-rotation-pass", o->noRotationPass,
                         "allow rotations (cycles of agents each following the next), as pibt2 does");
  trafficBench->add_option("--rotations", o->tb.rotations, "avoid | cancel | allow")->capture_default_str();
  trafficBench
      ->add_option("--escape-after", o->tb.escapeAfter,
                   "steps without coming closer to its goal before an agent is escalated (0: plain PIBT)")
      ->capture_default_str();
  trafficBench
      ->add_option("--escape-progress", o->tb.escapeProgress,
                   "cells an escalated agent gains on where it was escalated before it drops back")
      ->capture_default_str();
  trafficBench->add_flag("--mapd", o->tb.mapd,
                         "pickup and delivery (pibt2's MAPD setting) instead of lifelong MAPF");
  trafficBench->add_option("--pd", o->tb.pd,
                           "pibt2 .pd file: pickup, delivery and endpoint cells (with --mapd)");
  trafficBench->add_option("--tasks", o->tb.tasks, "MAPD: tasks in all")->capture_default_str();
  trafficBench->add_option("--frequency", o->tb.frequency, "MAPD: new tasks per step")->capture_default_str();
  trafficBench->add_option("--max-steps", o->tb.maxSteps, "MAPD: give up after this many steps")
      ->capture_default_str();
  commands.push_back({trafficBench, [o] {
                        if (o->noRotationPass) {
                          o->tb.rotations = "allow";
                        }
                        return runTrafficBench(o->tb);
                      }});
}

}  // namespace fleet::ctl
