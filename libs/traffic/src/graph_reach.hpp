#pragma once

// Which nodes of a graph can be reached from some (forward) or can reach them (backward) along
// passable edges, optionally never entering nodes marked in `avoid`: the roadmap's connectivity
// check and the queue check share it (roadmap_check.cpp, queue_check.cpp). Internal to libs/traffic.

#include <cstdint>
#include <span>
#include <vector>

#include "fleet/traffic/graph.hpp"

namespace fleet::traffic {

class GraphReach {
 public:
  /// Takes the graph as it is now (open and closed edges and nodes).
  explicit GraphReach(const Graph& g);
  /// 1 for every node reached, the seeds included; `avoid`, when not empty, has one entry per node.
  [[nodiscard]] std::vector<std::uint8_t> from(std::span<const NodeId> seeds, bool forward,
                                               std::span<const std::uint8_t> avoid = {}) const;

 private:
  const Graph& g_;
  std::vector<std::vector<NodeId>> in_;  ///< per node, who can drive into it
};

}  // namespace fleet::traffic
