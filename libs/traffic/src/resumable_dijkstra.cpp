// A detour table searched only as far as it is read (DistanceTable::startWithExtraCost / settle).
//
// The planner reads an agent's detour table at the agent's node and its neighbours (and, to
// untangle a knot, a few steps further): a Dijkstra from the goal that stops once those nodes are
// settled and resumes when the agent has moved gives them the very values a whole-graph search
// gives, having visited the nodes closer to the goal than the agent only (on the generated site
// for 300 robots ~1,200 of ~19,000 nodes on average: most detours are short, to a parking place or
// along a station's line). What the graph looked like when the detour was taken is kept in the
// per-node entering cost, a node that could not be entered then costing infinity, so a resumed
// search is the search that would have run to the end then.

#include <algorithm>
#include <functional>

#include "fleet/traffic/distance_table.hpp"

namespace fleet::traffic {

void DistanceTable::startWithExtraCost(NodeId goal, std::span<const float> extra, PartialTable& out) {
  if (dirty_) {
    invalidate();
  }
  const std::size_t n = graph_.size();
  out.goal = goal;
  out.dist.assign(n, kUnreachable);
  out.settled.assign((n + 63) / 64, 0);
  out.heap.clear();
  out.settledCount = 0;
  if (!graph_.valid(goal) || !graph_.isOpen(goal) || extra.size() != n) {
    out.enter.assign(n, kUnreachable);
    return;  // nothing reachable: an empty frontier
  }
  out.enter.resize(n);
  const bool nodeCost = nodeCost_.size() == n;
  for (std::size_t v = 0; v < n; ++v) {
    // The same float a whole search adds (extra + node cost); closed and blocked: never entered.
    const bool open = graph_.isOpen(static_cast<NodeId>(v)) && blocked_[v] == 0;
    out.enter[v] = !open ? kUnreachable : nodeCost ? extra[v] + nodeCost_[v] : extra[v];
  }
  const auto g = static_cast<std::size_t>(goal);
  out.enter[g] = 0.0F;  // arriving costs nothing; a blocked goal is still expanded
  out.dist[g] = 0.0F;
  out.heap.emplace_back(0.0F, goal);
}

float DistanceTable::settle(PartialTable& t, NodeId v) const {
  return settleIn(t, t.enter, v);
}

void DistanceTable::settleAround(PartialTable& t, NodeId v, int hops) const {
  settleAroundIn(t, t.enter, v, hops);
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
    if (du > t.dist[u] || t.isSettled(un)) {
      continue;
    }
    t.settled[u >> 6] |= std::uint64_t{1} << (u & 63);
    ++t.settledCount;
    const float enter = un == t.goal ? 0.0F : enterOf[u];
    if (enter != kUnreachable) {
      // Driving p→u costs the edge plus entering u (DistanceTable::dijkstra's expression).
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
  if (v == kNoNode) {
    return kUnreachable;
  }
  t.settled[want >> 6] |= std::uint64_t{1} << (want & 63);
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
