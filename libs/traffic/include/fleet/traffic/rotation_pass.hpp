#pragma once

// Rotations out of a one-step plan. Agent a *follows* agent b when a moves into a node that excludes
// b's node now (b has to leave first). A closed cycle of following — a rotation — is legal in the
// MAPF convention (everyone moves at the same instant), but robots executing the plan by
// dependencies each wait for the one ahead to leave: the cycle deadlocks. cancelRotations() makes
// every agent on a cycle wait, then every agent that was following one that now waits, and so on
// (a waiting agent still excludes its node). The result is again conflict-free and has no cycle.

#include <span>
#include <vector>

#include "fleet/traffic/graph.hpp"

namespace fleet::traffic {

class RotationPass {
 public:
  explicit RotationPass(const Graph& graph);

  /// `now` is conflict-free and `next` a conflict-free, swap-free step from it (kNoNode nowhere).
  /// Agents to stop get next[i] = now[i]. Returns how many agents were stopped (0: no rotation).
  std::size_t cancel(std::span<const NodeId> now, std::span<NodeId> next);

 private:
  /// The k-th node a robot at v excludes (k = 0: v itself), or kNoNode past the end.
  [[nodiscard]] NodeId excluded(NodeId v, std::size_t k) const;

  const Graph& graph_;
  std::vector<std::int32_t> agentAt_;     ///< node -> agent there now
  std::vector<std::int32_t> arrivingAt_;  ///< node -> moving agent going there
  std::vector<std::int32_t> index_;
  std::vector<std::int32_t> low_;
  std::vector<std::uint8_t> onStack_;
  std::vector<std::uint8_t> stop_;
  std::vector<std::int32_t> stack_;
  std::vector<std::pair<std::int32_t, std::size_t>> frames_;
  std::vector<std::int32_t> queue_;
};

}  // namespace fleet::traffic
