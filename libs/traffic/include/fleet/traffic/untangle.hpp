#pragma once

// A search over a few steps of a few agents for a knot PIBT cannot untie one step at a time
// (docs/algorithms.md, "Traffic: lifelong planner", "Untangling").
//
// The case: a robot parked in a dock whose only way out is excluded by a robot standing on the lane
// in front, which in turn wants to go where the parked one excludes. On a roadmap a node excludes
// more than its neighbours, so every single move the robot on the lane can make still excludes the
// dock's exit: priority inheritance fails whichever of the two goes first, and escalating one of
// them (PIBT's escape) fails the same way. Two moves of the robot on the lane, then one of the robot
// in the dock, untie it; only a search over several steps of both finds that.
//
// The search is breadth-first over joint configurations of the group, one agent moving per step
// (the others wait), everyone outside the group standing where they are. A move is allowed along an
// open edge into a node that is free of everyone outside the group and conflicts with no other
// member's node: since the others wait, nobody follows anybody within a step, so the steps need no
// rotation or swap rule and execute by dependencies like any other plan. It stops at the first
// configuration where a member that counts stands closer to its goal than it started.

#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <vector>

#include "fleet/traffic/graph.hpp"

namespace fleet::traffic {

struct UntangleProblem {
  /// The group's nodes now (at most kMaxUntangleGroup members).
  std::vector<NodeId> starts;
  /// Per member: distances to its goal (indexed by node), nullptr when it has none.
  std::vector<const float*> tables;
  /// Per member: whether coming closer to its goal ends the search (the knot's own members; helpers
  /// pulled in to make room do not count).
  std::vector<std::uint8_t> counts;
  /// Whether a member may stand on (or drive into) v as far as everyone outside the group goes: v
  /// and what it excludes hold nobody else.
  std::function<bool(NodeId)> clearOfOthers;
  /// Whether member i may move from one node to the next at all (a robot waiting in a station's
  /// line moves only forward along it); empty: every open edge.
  std::function<bool(std::size_t member, NodeId from, NodeId to)> mayMove{};
  int maxSteps = 12;
  std::size_t maxConfigurations = 20000;
};

struct UntangleResult {
  /// Per step the members' nodes, starting with the starts; consecutive entries differ in at most
  /// one member.
  std::vector<std::vector<NodeId>> steps;
  /// The member that came closer to its goal.
  std::size_t improved = 0;
};

inline constexpr std::size_t kMaxUntangleGroup = 4;

/// The shortest sequence of single moves after which a counting member is closer to its goal, or
/// nothing within maxSteps / maxConfigurations. std::invalid_argument for more than
/// kMaxUntangleGroup members or vectors of different lengths.
std::optional<UntangleResult> untangle(const Graph& graph, const UntangleProblem& problem);

}  // namespace fleet::traffic
