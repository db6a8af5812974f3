#pragma once

// `fleetctl traffic-bench`: the lifelong planner alone on a MovingAI grid, in grid units (a move to a
// 4-neighbour or a wait per step, the MAPF convention), so its figures compare with the literature's
// and anyone can check the written plan with an independent checker (scripts/check-plan.py).
//
// Lifelong MAPF (default): N agents on random distinct cells (or on a .scen file's starts, heading
// first for its goals), each given a new random goal as soon as it reaches one; prints throughput
// (goals reached per step) and planning time per step.
// MAPD (--mapd --pd FILE.pd): Kei18/pibt2's pickup-and-delivery setting — tasks appear at a
// frequency between random pickup and delivery cells of the .pd file, a free agent heads for the
// nearest open pickup and takes the task when it gets there; prints service time, makespan and
// computation time the way pibt2's `mapd` does, so the two compare line by line.

#include <cstdint>
#include <string>

namespace fleet::ctl {

struct TrafficBenchOptions {
  std::string map;
  /// MovingAI .scen for the same map: agent i starts (and first heads) where its i-th usable row
  /// says; empty: random distinct cells.
  std::string scen;
  int agents = 100;
  int steps = 1000;
  std::uint64_t seed = 1;
  std::string out;                  ///< plan.json; empty: not written
  std::string rotations = "avoid";  ///< avoid | cancel | allow (--no-rotation-pass: allow)
  int escapeAfter = 16;             ///< 0: plain PIBT
  double escapeProgress = 16.0;     ///< see PibtOptions::escapeProgress
  bool mapd = false;
  std::string pd;
  int tasks = 500;
  double frequency = 1.0;
  int maxSteps = 3000;  ///< MAPD: give up after this many steps (pibt2's max_timestep)
};

/// Exit code: 0 done, 1 MAPD not finished within maxSteps, 2 bad input (named on stderr).
int runTrafficBench(const TrafficBenchOptions& options);

}  // namespace fleet::ctl
