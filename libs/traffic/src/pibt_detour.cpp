// Detours round standing robots (PibtOptions::detourAfter; docs/algorithms.md, "Detours round
// standing robots") and the settling of every agent's table where the planner reads it ("Tables
// searched only as far as they are read").

#include <cmath>
#include <vector>

#include "fleet/traffic/pibt.hpp"
#include "pibt_index.hpp"

namespace fleet::traffic {

using pibt_detail::idx;

void Pibt::dropDetour(std::size_t agent) {
  if (!detour_[agent].empty()) {
    detour_[agent].clear();
    best_[agent] = DistanceTable::kUnreachable;
  }
}

void Pibt::planDetours() {
  const std::size_t n = now_.size();
  int budget = options_.maxDetoursPerStep;
  bool covered = false;
  std::vector<int>& cover = standCover_;
  for (std::size_t i = 0; i < n; ++i) {
    if (controlled_[i] == 0 || goal_[i] == kNoNode || now_[i] == goal_[i]) {
      dropDetour(i);
      continue;
    }
    if (!detour_[i].empty() && (distances_.distance(now_[i], goal_[i]) < detourFrom_[i] || !nearDetour(i))) {
      dropDetour(i);  // past what it went round, or out of its disc: the shortest way again
    }
    if (budget == 0 || stalled_[i] < options_.detourAfter || still_[i] < options_.detourAfter) {
      continue;
    }
    if (!covered) {
      // What every agent that has stood still as long excludes, counted per node.
      cover.assign(graph_.size(), 0);
      for (std::size_t b = 0; b < n; ++b) {
        if (controlled_[b] != 0 && still_[b] >= options_.detourAfter) {
          ++cover[idx(now_[b])];
          for (const NodeId w : graph_.conflicts(now_[b])) {
            ++cover[idx(w)];
          }
        }
      }
      covered = true;
    }
    // Its own footprint is no obstacle to it: there only the others standing count.
    extra_.resize(graph_.size());
    for (std::size_t v = 0; v < graph_.size(); ++v) {
      extra_[v] = cover[v] > 0 ? options_.detourPenalty : 0.0F;
    }
    const auto own = [&](NodeId w) { extra_[idx(w)] = cover[idx(w)] > 1 ? options_.detourPenalty : 0.0F; };
    own(now_[i]);
    for (const NodeId w : graph_.conflicts(now_[i])) {
      own(w);
    }
    const float from = distances_.distance(now_[i], goal_[i]);
    distances_.detourAround(goal_[i], now_[i], options_.detourRadius, extra_, detour_[i]);
    detourAt_[i] = now_[i];
    --budget;
    ++stats_.detours;
    const float there = distances_.settle(detour_[i], now_[i]);
    if (there == DistanceTable::kUnreachable) {
      detour_[i].clear();
      continue;
    }
    detourFrom_[i] = from;
    best_[i] = there;
    stalled_[i] = 0;
  }
  settleTables();
}

bool Pibt::nearDetour(std::size_t i) const {
  const Vec2 a = graph_.position(now_[i]);
  const Vec2 b = graph_.position(detourAt_[i]);
  return std::hypot(a.x - b.x, a.y - b.y) <= options_.detourKeep;
}

void Pibt::settleTable(std::size_t i, int hops) {
  if (controlled_[i] == 0 || goal_[i] == kNoNode) {
    return;
  }
  if (detour_[i].empty()) {
    distances_.settleAround(goal_[i], now_[i], hops);
  } else {
    distances_.settleAround(detour_[i], now_[i], hops);
  }
}

void Pibt::settleTables() {
  for (std::size_t i = 0; i < now_.size(); ++i) {
    settleTable(i, 1);
  }
}

}  // namespace fleet::traffic
