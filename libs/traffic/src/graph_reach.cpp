#include "graph_reach.hpp"

#include <deque>

namespace fleet::traffic {

GraphReach::GraphReach(const Graph& g) : g_(g), in_(g.size()) {
  for (NodeId v = 0; static_cast<std::size_t>(v) < g.size(); ++v) {
    for (const auto& e : g.edges(v)) {
      if (g.passable(v, e))
        in_[static_cast<std::size_t>(e.to)].push_back(v);
    }
  }
}

std::vector<std::uint8_t> GraphReach::from(std::span<const NodeId> seeds, bool forward,
                                           std::span<const std::uint8_t> avoid) const {
  std::vector<std::uint8_t> seen(g_.size(), 0);
  std::deque<NodeId> q;
  const auto visit = [&](NodeId w) {
    const auto i = static_cast<std::size_t>(w);
    if (!seen[i] && (avoid.empty() || !avoid[i])) {
      seen[i] = 1;
      q.push_back(w);
    }
  };
  for (const NodeId s : seeds) {
    if (!seen[static_cast<std::size_t>(s)]) {
      seen[static_cast<std::size_t>(s)] = 1;
      q.push_back(s);
    }
  }
  while (!q.empty()) {
    const NodeId v = q.front();
    q.pop_front();
    if (forward) {
      for (const auto& e : g_.edges(v)) {
        if (g_.passable(v, e))
          visit(e.to);
      }
    } else {
      for (const NodeId w : in_[static_cast<std::size_t>(v)])
        visit(w);
    }
  }
  return seen;
}

}  // namespace fleet::traffic
