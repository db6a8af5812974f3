#pragma once

// An independent check of a whole plan (every agent's node at every step), written apart from the
// planner so that it can catch the planner's mistakes: every move follows an open edge (or waits),
// no two agents stand on conflicting nodes, no two agents swap (each moves into what the other
// excludes now), and optionally no rotation (a closed cycle of agents each following the next).

#include <cstddef>
#include <span>
#include <string>
#include <vector>

#include "fleet/traffic/graph.hpp"

namespace fleet::traffic {

enum class ViolationKind { kBadNode, kNoEdge, kVertex, kSwap, kRotation, kAgentCount };

struct Violation {
  ViolationKind kind = ViolationKind::kBadNode;
  std::size_t step = 0;             ///< the configuration index where it shows (a move t-1 -> t: t)
  std::vector<std::size_t> agents;  ///< the agents involved (a rotation: the whole cycle)
  std::vector<NodeId> nodes;        ///< their nodes at `step` (for a move: from, to)
};

struct PlanCheckOptions {
  bool rotations = true;           ///< report rotation cycles too
  std::size_t maxViolations = 10;  ///< stop after this many
};

/// `configs[t][i]` is agent i's node at step t. Returns the first violations in step order (empty:
/// the plan is valid).
std::vector<Violation> checkPlan(const Graph& graph, std::span<const std::vector<NodeId>> configs,
                                 const PlanCheckOptions& options = {});

std::string describe(const Violation& v);
const char* toString(ViolationKind kind);

}  // namespace fleet::traffic
