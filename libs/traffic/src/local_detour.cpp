// A detour table searched round the agent only (DistanceTable::detourAround).
//
// A detour routes an agent round robots that have stood in its way for a while (Pibt's detours):
// what it has to go round is near it, and robots standing far off will have moved by the time it
// gets there. The whole-graph search it replaced paid for the far end too: with every way past a
// standing robot costing the penalty, it settled most of the roadmap (at 300 robots half the
// planner's time, up to four a step). This one searches a disc round the agent's node: the nodes
// it can reach without leaving the disc, each leaving it valued at the goal table's distance (no
// penalty out there), inside the penalties as before. The agent drops the detour once it has left
// the disc's inner part (Pibt::planDetours), so it never reads the values near the rim.

#include <algorithm>
#include <cmath>
#include <functional>

#include "fleet/traffic/distance_table.hpp"

namespace fleet::traffic {

void DistanceTable::detourAround(NodeId goal, NodeId from, double radius, std::span<const float> extra,
                                 PartialTable& out) {
  if (dirty_ || !changed_.empty()) {
    applyChanges();
  }
  const std::size_t n = graph_.size();
  out.reset(goal, n);
  if (!graph_.valid(goal) || !graph_.valid(from) || !graph_.isOpen(goal) || extra.size() != n) {
    out.goal = kNoNode;
    return;
  }
  // The disc: nodes reachable from `from` along open edges without leaving it.
  const Vec2 c = graph_.position(from);
  const double r2 = radius * radius;
  const auto inside = [&](NodeId v) {
    const Vec2 p = graph_.position(v);
    return (p.x - c.x) * (p.x - c.x) + (p.y - c.y) * (p.y - c.y) <= r2;  // hypot's care for overflow costs
  };
  auto& region = region_;
  region.clear();
  region.push_back(from);
  inRegion_.resize(n, 0);
  inRegion_[static_cast<std::size_t>(from)] = 1;
  for (std::size_t head = 0; head < region.size(); ++head) {
    for (const Edge& e : graph_.edges(region[head])) {
      const auto w = static_cast<std::size_t>(e.to);
      if (e.open && inRegion_[w] == 0 && inside(e.to)) {
        inRegion_[w] = 1;
        region.push_back(e.to);
      }
    }
  }
  // Entering a node inside costs its penalty as in a whole detour search; the way on from a node
  // outside is the goal table's (no penalty: what stands out there is not what the agent goes round).
  const auto enter = [&](std::size_t u) {
    return static_cast<NodeId>(u) == goal  ? 0.0F
           : baseEnter_[u] == kUnreachable ? kUnreachable
                                           : baseEnter_[u] + extra[u];
  };
  auto& heap = out.heap;
  const auto later = std::greater<>{};
  for (const NodeId u : region) {
    float best = u == goal ? 0.0F : kUnreachable;
    for (const Edge& e : graph_.edges(u)) {
      const auto w = static_cast<std::size_t>(e.to);
      if (!e.open || inRegion_[w] != 0 || baseEnter_[w] == kUnreachable) {
        continue;
      }
      const float on = distance(e.to, goal);
      if (on != kUnreachable) {
        best = std::min(best, on + static_cast<float>(e.cost()) + baseEnter_[w]);
      }
    }
    if (best != kUnreachable) {
      out.dist[static_cast<std::size_t>(u)] = best;
      heap.emplace_back(best, u);
    }
  }
  std::make_heap(heap.begin(), heap.end(), later);
  while (!heap.empty()) {
    std::pop_heap(heap.begin(), heap.end(), later);
    const auto [du, un] = heap.back();
    heap.pop_back();
    const auto u = static_cast<std::size_t>(un);
    if (du > out.dist[u] || out.isSettled(un)) {
      continue;
    }
    out.settled[u >> 6] |= std::uint64_t{1} << (u & 63);
    const float e = enter(u);
    if (e == kUnreachable) {
      continue;  // closed or blocked: it learns its way off, nobody drives in
    }
    for (std::uint32_t k = revStart_[u]; k < revStart_[u + 1]; ++k) {
      const NodeId p = revFrom_[k];
      const auto pi = static_cast<std::size_t>(p);
      if (inRegion_[pi] == 0) {
        continue;
      }
      const float nd = du + revDuration_[k] + e;
      if (nd < out.dist[pi]) {
        out.dist[pi] = nd;
        heap.emplace_back(nd, p);
        std::push_heap(heap.begin(), heap.end(), later);
      }
    }
  }
  // Every node is final: inside as searched, outside never read (unreachable).
  std::fill(out.settled.begin(), out.settled.end(), ~std::uint64_t{0});
  out.settledCount = n;
  for (const NodeId u : region) {
    inRegion_[static_cast<std::size_t>(u)] = 0;
  }
  region.clear();
}

}  // namespace fleet::traffic
