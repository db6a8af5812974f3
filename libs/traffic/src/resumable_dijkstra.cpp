// A goal's table searched only as far as it is read (DistanceTable::distance / settle).
//
// The planner reads an agent's table at the agent's node and its neighbours (and, to untangle a
// knot, a few steps further): a Dijkstra from the goal that stops once those nodes are settled and
// resumes when another agent reads further off gives them the very values a whole-graph search
// gives, having visited the nodes closer to the goal than the agents only. Each node's entering
// cost is read when the node is settled, which is what lets a change of it restart only the tables
// that have settled the node (DistanceTable::applyChanges).

#include <algorithm>
#include <functional>

#include "fleet/traffic/distance_table.hpp"

namespace fleet::traffic {

float DistanceTable::settle(PartialTable& t, NodeId v) const {
  return settleIn(t, baseEnter_, v);
}

void DistanceTable::settleAround(PartialTable& t, NodeId v, int hops) const {
  settleAroundIn(t, baseEnter_, v, hops);
}

float DistanceTable::settleIn(PartialTable& t, std::span<const float> enterOf, NodeId v) const {
  // v == kNoNode: to the end of the search.
  const auto want = v == kNoNode ? graph_.size() : static_cast<std::size_t>(v);
  if (t.empty()) {
    return kUnreachable;
  }
  if (v != kNoNode && t.isSettled(v)) {
    return t.dist[want];
  }
  const auto later = std::greater<>{};
  auto& heap = t.heap;
  while (!heap.empty()) {
    std::pop_heap(heap.begin(), heap.end(), later);
    const auto [du, un] = heap.back();
    heap.pop_back();
    const auto u = static_cast<std::size_t>(un);
    // An entry is stale unless it holds the node's distance (a repair may have raised it).
    if (du != t.dist[u] || t.isSettled(un)) {
      continue;
    }
    t.settled[u >> 6] |= std::uint64_t{1} << (u & 63);
    ++t.settledCount;
    t.radius = std::max(t.radius, du);
    const float enter = un == t.goal ? 0.0F : enterOf[u];
    if (enter != kUnreachable) {
      // Driving p→u costs the edge plus entering u (a node's entering cost is paid by whoever drives in).
      for (std::uint32_t k = revStart_[u]; k < revStart_[u + 1]; ++k) {
        const NodeId p = revFrom_[k];
        const float nd = du + revDuration_[k] + enter;
        auto& dp = t.dist[static_cast<std::size_t>(p)];
        if (nd < dp) {
          dp = nd;
          heap.emplace_back(nd, p);
          std::push_heap(heap.begin(), heap.end(), later);
        }
      }
    }
    if (u == want) {
      return t.dist[want];
    }
  }
  // Frontier exhausted: every node left is unreachable (its bound is infinite), hence final.
  t.radius = kUnreachable;
  if (v == kNoNode) {
    return kUnreachable;
  }
  if (!t.isSettled(v)) {
    t.settled[want >> 6] |= std::uint64_t{1} << (want & 63);
    ++t.settledCount;
  }
  return t.dist[want];
}

void DistanceTable::settleAroundIn(PartialTable& t, std::span<const float> enterOf, NodeId v,
                                   int hops) const {
  if (t.empty() || !graph_.valid(v)) {
    return;
  }
  settleIn(t, enterOf, v);
  if (hops <= 0) {
    return;
  }
  if (hops == 1) {  // every step, for every agent on a detour: no allocation
    for (const Edge& e : graph_.edges(v)) {
      settleIn(t, enterOf, e.to);
    }
    return;
  }
  std::vector<std::pair<NodeId, int>> frontier{{v, 0}};
  std::vector<NodeId> seen{v};
  for (std::size_t head = 0; head < frontier.size(); ++head) {
    const auto [u, depth] = frontier[head];
    for (const Edge& e : graph_.edges(u)) {
      if (std::find(seen.begin(), seen.end(), e.to) != seen.end()) {
        continue;
      }
      seen.push_back(e.to);
      settleIn(t, enterOf, e.to);
      if (depth + 1 < hops) {
        frontier.emplace_back(e.to, depth + 1);
      }
    }
  }
}

}  // namespace fleet::traffic
