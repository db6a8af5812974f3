#pragma once

// Prioritized planning over safe intervals, windowed (Silver's cooperative A*, in continuous time
// with SIPP as the single-robot search; Li et al.'s rolling-horizon collision resolution, RHCR,
// AAAI 2021, for the window): robots are planned one after another in priority order, each the
// earliest timed path (sipp.hpp) that keeps to the reservations of those planned before it. A robot
// not planned yet stands where it is, so its node is unsafe from when it stands there until it is
// planned; a robot that finds no path stays where it stands (its node stays reserved) — the plan is
// free of conflicts whatever is found. Reservations count only within `window` s of the plan's
// start: later conflicts are left to the next plan, made well before then (a lifelong planner plans
// again every few seconds from where the robots are).
//
// A robot standing where it is until it is planned blocks those planned before it. When a robot
// finds no path, the robots standing on its way (as it would drive with nobody standing) inherit its
// priority: they are planned just before it, each to its own goal if it can get there, else to the
// earliest refuge off that way (a siding, a lane beside), and everyone is planned again
// (`yieldRounds` times at most; a robot yielding does not make the one it yields to yield back).
// This is PIBT's priority inheritance in time instead of in one step.
//
// Held robots (faulted, docking, a vendor's vehicle) are obstacles for good. A robot without a goal
// stays where it is unless it stands on the way of a robot that failed.

#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "fleet/traffic/graph.hpp"
#include "fleet/traffic/safe_intervals.hpp"
#include "fleet/traffic/sipp.hpp"

namespace fleet::traffic {

struct PlanRequest {
  NodeId at = kNoNode;        ///< where it stands from `ready` on
  NodeId cameFrom = kNoNode;  ///< its heading there (kNoNode: none)
  double ready = 0.0;         ///< s: from when
  NodeId goal = kNoNode;      ///< kNoNode: none (it stays)
  int priority = 0;           ///< higher first; ties: the longer waiting since its last goal first
  double waiting = 0.0;       ///< s since it last reached a goal (the fairness tie-break)
  bool held = false;          ///< an obstacle on `at` for good
  /// The station line it waits in, -1: on that line's nodes it moves only forward and is never
  /// sent out of another's way (it would lose its place).
  std::int32_t line = -1;
  /// What it was released already and drives before `ready` (ends on `at`): reserved as it is,
  /// and `at` from the first node's `enter` on (a plan executed by dependencies has the robot on
  /// `at` before any move planned now: nobody may plan into what `at` excludes before it).
  TimedPath committed;
};

struct PrioritizedOptions {
  double window = 5.0;  ///< s of reservations that count (from the earliest ready)
  /// States per robot's search. A search that runs out is a robot whose way is shut: on the site for
  /// 100 with 100 robots those were three fifths of every state searched at 5,000; at 2,000 the
  /// virtual fleet does as many tasks (docs/algorithms.md, "What a search costs").
  std::size_t maxExpansions = 2000;
  int yieldRounds = 1;  ///< plans again with robots yielding at most this often
  /// A robot that is where its last plan has it within this many s keeps the rest of that plan
  /// when it still keeps to the reservations (no search).
  double reuseSlack = 0.5;
};

struct PrioritizedStats {
  std::uint64_t plans = 0;
  std::uint64_t failures = 0;  ///< robots with a goal not planned to it (no path found)
  std::uint64_t yields = 0;    ///< robots planned before one whose way they stood on
  std::uint64_t refuges = 0;   ///< robots planned out of another's way instead of to their goal
  std::uint64_t deferred = 0;  ///< robots planned again after the others (their way was shut)
  std::uint64_t reused = 0;    ///< robots that kept the rest of their last plan
};

class PrioritizedPlanner {
 public:
  PrioritizedPlanner(const Graph& graph, Sipp::TurnTime turn = {}, PrioritizedOptions options = {});

  /// One timed path per request (the first node `at` from `ready`; the last stays there: leave =
  /// kForever). Robots' `at` nodes must not conflict.
  std::vector<TimedPath> plan(std::span<const PlanRequest> robots);

  /// The order plan() takes the robots in (held first, then by priority, goal, waiting, index).
  [[nodiscard]] static std::vector<std::size_t> order(std::span<const PlanRequest> robots);
  /// Station lines: per node, the line it belongs to (-1) and the next node toward the dock.
  void setLines(std::vector<std::int32_t> lineOf, std::vector<NodeId> forward) {
    lineOf_ = std::move(lineOf);
    forward_ = std::move(forward);
  }

  [[nodiscard]] const PrioritizedStats& stats() const { return stats_; }
  /// The last plan's window ends then (s): its paths are free of conflicts before it.
  [[nodiscard]] double windowEnd() const { return until_; }
  [[nodiscard]] const SippStats& searchStats() const { return sipp_.stats(); }
  /// Call after opening or closing nodes or edges: drops the heuristics and the plans kept.
  void graphChanged() {
    sipp_.graphChanged();
    previous_.clear();
  }
  /// A standing cost (s) of driving into each node (Sipp::setNodeCost); a plan kept through a node
  /// whose cost changed is searched again, and every kept plan once a node anywhere is a second or
  /// more cheaper (a yield's end: a way round it may no longer be the earliest).
  void setNodeCost(std::vector<float> cost);
  [[nodiscard]] const std::vector<float>& nodeCost() const { return sipp_.nodeCost(); }

 private:
  void reserveFixed(std::span<const PlanRequest> robots, bool starts);
  [[nodiscard]] std::optional<TimedPath> reuse(std::size_t i, const PlanRequest& r) const;
  [[nodiscard]] bool keepsPlace(const PlanRequest& r) const;
  std::vector<std::size_t> pass(std::span<const PlanRequest> robots, std::span<const std::size_t> order,
                                const std::vector<std::vector<std::uint8_t>>& clear, double until,
                                std::vector<TimedPath>& paths);

  const Graph& graph_;
  PrioritizedOptions options_;
  Sipp sipp_;
  ReservationTable table_;
  PrioritizedStats stats_;
  std::vector<std::int32_t> lineOf_;
  std::vector<NodeId> forward_;
  std::vector<TimedPath> previous_;  ///< per robot: its path in the last plan
  double until_ = 0.0;
};

}  // namespace fleet::traffic
