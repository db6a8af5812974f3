// The planner's agents between steps: where they stand, where they go, which the planner moves,
// the lines they belong to, and a reset to new positions. The step itself is in pibt.cpp.

#include <algorithm>
#include <stdexcept>
#include <string>

#include "fleet/traffic/pibt.hpp"
#include "pibt_index.hpp"

namespace fleet::traffic {

using pibt_detail::idx;

Pibt::Pibt(const Graph& graph, std::span<const NodeId> starts, PibtOptions options)
    : graph_(graph),
      options_(options),
      distances_(graph, options.distanceCacheBytes),
      rotationPass_(graph),
      rng_(options.seed) {
  const std::size_t n = starts.size();
  now_.assign(starts.begin(), starts.end());
  next_.assign(n, kNoNode);
  prev_.assign(n, kNoNode);
  goal_.assign(n, kNoNode);
  table_.assign(n, nullptr);
  surcharge_.assign(n, nullptr);
  if (options_.turnTime) {
    heading_ = std::make_unique<HeadingTable>(graph, options_.turnTime, options_.headingCacheBytes);
  }
  task_.assign(n, 0);
  elapsed_.assign(n, 0);
  controlled_.assign(n, 1);
  onStack_.assign(n, 0);
  best_.assign(n, DistanceTable::kUnreachable);
  stalled_.assign(n, 0);
  escalatedAt_.assign(n, -1);
  escalationDraw_.assign(n, 0);
  escalationDistance_.assign(n, 0.0F);
  escalationIdle_.assign(n, 0);
  still_.assign(n, 0);
  detour_.assign(n, {});
  detourFrom_.assign(n, 0.0F);
  detourAt_.assign(n, kNoNode);
  tries_.assign(n, 0);
  visited_.assign(n, 0);
  forced_.assign(n, {});
  forcedAt_.assign(n, 0);
  forcedGroup_.assign(n, -1);
  line_.assign(n, -1);
  epsilon_.resize(n);
  for (auto& e : epsilon_) {
    e = static_cast<double>(random() >> 11) * 0x1.0p-53;
  }
  resizeForGraph();
  std::fill(agentAt_.begin(), agentAt_.end(), -1);
  for (std::size_t i = 0; i < n; ++i) {
    const NodeId v = now_[i];
    if (!graph_.valid(v)) {
      throw std::invalid_argument("Pibt: agent " + std::to_string(i) + " starts on invalid node " +
                                  std::to_string(v));
    }
    const std::int32_t other = standingOn(v, static_cast<std::int32_t>(i));
    if (other >= 0) {
      throw std::invalid_argument("Pibt: agents " + std::to_string(other) + " and " + std::to_string(i) +
                                  " start on conflicting nodes " + std::to_string(now_[idx(other)]) +
                                  " and " + std::to_string(v));
    }
    agentAt_[idx(v)] = static_cast<std::int32_t>(i);
  }
  order_.reserve(n);
}

std::uint64_t Pibt::random() {
  // splitmix64: tiny, fast and the same on every platform (std distributions are not).
  std::uint64_t z = (rng_ += 0x9e3779b97f4a7c15ULL);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

void Pibt::resizeForGraph() {
  grid_ = !graph_.hasConflicts();
  std::size_t maxDegree = 0;
  for (std::size_t v = 0; v < graph_.size(); ++v) {
    maxDegree = std::max(maxDegree, graph_.edges(static_cast<NodeId>(v)).size());
  }
  stride_ = maxDegree + 1;
  candidates_.assign(stride_ * (now_.size() + 1), Candidate{kNoNode, 0.0F, 0});
  if (agentAt_.size() != graph_.size()) {
    agentAt_.assign(graph_.size(), -1);
    for (std::size_t i = 0; i < now_.size(); ++i) {
      if (graph_.valid(now_[i])) {
        agentAt_[idx(now_[i])] = static_cast<std::int32_t>(i);
      }
    }
  }
  reservedBy_.assign(graph_.size(), -1);
  search_.reserve(now_.size());
  fixedCover_.resize(graph_.size(), 0);
}

void Pibt::graphChanged() {
  distances_.invalidate();
  if (heading_) {
    heading_->invalidate();
  }
  resizeForGraph();
  std::fill(table_.begin(), table_.end(), nullptr);
  std::fill(surcharge_.begin(), surcharge_.end(), nullptr);
  std::fill(best_.begin(), best_.end(), DistanceTable::kUnreachable);
  for (auto& d : detour_) {
    d.clear();
  }
}

void Pibt::setNodeCost(std::vector<float> cost) {
  rebaseProgress_ = distances_.setNodeCost(std::move(cost)) || rebaseProgress_;
}

void Pibt::setGoal(std::size_t agent, NodeId goal) {
  if (goal != kNoNode && !graph_.valid(goal)) {
    throw std::invalid_argument("Pibt::setGoal: invalid node " + std::to_string(goal));
  }
  if (goal_[agent] == goal) {
    return;
  }
  goal_[agent] = goal;
  dropDetour(agent);
  best_[agent] = DistanceTable::kUnreachable;
  stalled_[agent] = 0;
  tries_[agent] = 0;
  escalatedAt_[agent] = -1;
}

void Pibt::cover(NodeId v, int delta) {
  // Routes avoid what a fixed robot excludes (its node and, on a roadmap, its conflict set): plain
  // PIBT only ever moves greedily, so without this an agent would wait behind it for ever.
  const auto apply = [&](NodeId w) {
    auto& c = fixedCover_[idx(w)];
    c += delta;
    distances_.setBlocked(w, c > 0);
  };
  apply(v);
  for (const NodeId w : graph_.conflicts(v)) {
    apply(w);
  }
}

void Pibt::setControlled(std::size_t agent, bool controlled) {
  if ((controlled_[agent] != 0) != controlled) {
    cover(now_[agent], controlled ? -1 : 1);
  }
  controlled_[agent] = controlled ? 1 : 0;
  dropForced(forcedGroup_[agent]);
  dropDetour(agent);
  escalatedAt_[agent] = -1;
  stalled_[agent] = 0;
}

std::int32_t Pibt::standingOn(NodeId v, std::int32_t except) const {
  std::int32_t o = agentAt_[idx(v)];
  if (o >= 0 && o != except) {
    return o;
  }
  for (const NodeId w : graph_.conflicts(v)) {
    o = agentAt_[idx(w)];
    if (o >= 0 && o != except) {
      return o;
    }
  }
  return -1;
}

bool Pibt::setPosition(std::size_t agent, NodeId v) {
  if (!graph_.valid(v) || standingOn(v, static_cast<std::int32_t>(agent)) >= 0) {
    return false;
  }
  if (controlled_[agent] == 0) {
    cover(now_[agent], -1);
    cover(v, 1);
  }
  dropForced(forcedGroup_[agent]);
  agentAt_[idx(now_[agent])] = -1;
  if (now_[agent] != v)
    prev_[agent] = kNoNode;
  now_[agent] = v;
  agentAt_[idx(v)] = static_cast<std::int32_t>(agent);
  best_[agent] = DistanceTable::kUnreachable;
  stalled_[agent] = 0;
  return true;
}

void Pibt::setLines(std::vector<std::int32_t> lineOf, std::vector<NodeId> forward) {
  if (!lineOf.empty() && (lineOf.size() != graph_.size() || forward.size() != graph_.size())) {
    throw std::invalid_argument("Pibt::setLines: one line and one forward node per graph node");
  }
  lineOf_ = std::move(lineOf);
  lineForward_ = std::move(forward);
}

void Pibt::setLine(std::size_t agent, std::int32_t line) {
  line_.at(agent) = line;
}

void Pibt::reset(std::span<const NodeId> positions, std::span<const NodeId> cameFrom) {
  if (positions.size() < now_.size()) {
    throw std::invalid_argument("Pibt::reset: " + std::to_string(positions.size()) + " positions for " +
                                std::to_string(now_.size()) + " agents");
  }
  // Check first: nothing changes when the new configuration is refused.
  std::vector<std::int32_t> at(graph_.size(), -1);
  for (std::size_t i = 0; i < positions.size(); ++i) {
    const NodeId v = positions[i];
    if (!graph_.valid(v)) {
      throw std::invalid_argument("Pibt::reset: agent " + std::to_string(i) + " on invalid node " +
                                  std::to_string(v));
    }
    at[idx(v)] = at[idx(v)] >= 0 ? -2 : static_cast<std::int32_t>(i);
  }
  for (std::size_t i = 0; i < positions.size(); ++i) {
    const NodeId v = positions[i];
    bool clash = at[idx(v)] == -2;
    for (const NodeId w : graph_.conflicts(v))
      clash = clash || at[idx(w)] != -1;
    if (clash) {
      throw std::invalid_argument("Pibt::reset: agent " + std::to_string(i) + " on node " +
                                  std::to_string(v) + " conflicts with another agent");
    }
  }
  for (std::size_t i = 0; i < now_.size(); ++i) {
    if (controlled_[i] == 0)
      cover(now_[i], -1);
    agentAt_[idx(now_[i])] = -1;
  }
  const std::size_t old = now_.size();
  const std::size_t n = positions.size();
  if (n > old) {
    next_.resize(n, kNoNode);
    goal_.resize(n, kNoNode);
    table_.resize(n, nullptr);
    surcharge_.resize(n, nullptr);
    task_.resize(n, 0);
    elapsed_.resize(n, 0);
    controlled_.resize(n, 1);
    onStack_.resize(n, 0);
    best_.resize(n, DistanceTable::kUnreachable);
    stalled_.resize(n, 0);
    escalatedAt_.resize(n, -1);
    escalationDraw_.resize(n, 0);
    escalationDistance_.resize(n, 0.0F);
    escalationIdle_.resize(n, 0);
    still_.resize(n, 0);
    prev_.resize(n, kNoNode);
    detour_.resize(n);
    detourFrom_.resize(n, 0.0F);
    detourAt_.resize(n, kNoNode);
    tries_.resize(n, 0);
    visited_.resize(n, 0);
    forced_.resize(n);
    forcedAt_.resize(n, 0);
    forcedGroup_.resize(n, -1);
    line_.resize(n, -1);
    for (std::size_t i = old; i < n; ++i)
      epsilon_.push_back(static_cast<double>(random() >> 11) * 0x1.0p-53);
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (i < old && now_[i] != positions[i]) {
      // Where it was planned to be is gone: its progress is measured afresh.
      best_[i] = DistanceTable::kUnreachable;
      stalled_[i] = 0;
      prev_[i] = kNoNode;
    }
    // A heading is an edge into the new position; anything else is no heading.
    if (i < cameFrom.size() && graph_.valid(cameFrom[i])) {
      const auto into = graph_.edges(cameFrom[i]);
      if (std::any_of(into.begin(), into.end(), [&](const Edge& e) { return e.to == positions[i]; })) {
        prev_[i] = cameFrom[i];
      }
    }
  }
  // A way out of a knot goes on from where the new positions are on it (the robots were released
  // part of it), else it is given up.
  for (std::size_t i = 0; i < old; ++i) {
    const std::int32_t g = forcedGroup_[i];
    if (g < 0)
      continue;  // (each member of a group finds the same place: done again, no harm)
    std::size_t place = forced_[i].size();
    for (std::size_t k = forced_[i].size(); k-- > 0;) {
      bool all = true;
      for (std::size_t j = 0; j < old && all; ++j)
        all = forcedGroup_[j] != g || forced_[j][k] == positions[j];
      if (all) {
        place = k;
        break;
      }
    }
    if (place + 1 >= forced_[i].size()) {
      dropForced(g);  // not on it, or at its end
      continue;
    }
    for (std::size_t j = 0; j < old; ++j) {
      if (forcedGroup_[j] == g)
        forcedAt_[j] = place;
    }
  }
  now_.assign(positions.begin(), positions.end());
  for (std::size_t i = 0; i < n; ++i) {
    agentAt_[idx(now_[i])] = static_cast<std::int32_t>(i);
    if (controlled_[i] == 0)
      cover(now_[i], 1);
  }
  if (n > old) {
    candidates_.assign(stride_ * (n + 1), Candidate{kNoNode, 0.0F, 0});
    order_.reserve(n);
    search_.reserve(n);
    distances_.reserve(n + 1);
  }
}

}  // namespace fleet::traffic
