#include "fleet/traffic/rotation_pass.hpp"

#include <algorithm>

namespace fleet::traffic {

RotationPass::RotationPass(const Graph& graph)
    : graph_(graph), agentAt_(graph.size(), -1), arrivingAt_(graph.size(), -1) {}

NodeId RotationPass::excluded(NodeId v, std::size_t k) const {
  if (k == 0) {
    return v;
  }
  const auto c = graph_.conflicts(v);
  return k - 1 < c.size() ? c[k - 1] : kNoNode;
}

std::size_t RotationPass::cancel(std::span<const NodeId> now, std::span<NodeId> next) {
  const std::size_t n = now.size();
  if (agentAt_.size() != graph_.size()) {
    agentAt_.assign(graph_.size(), -1);
    arrivingAt_.assign(graph_.size(), -1);
  }
  index_.assign(n, -1);
  low_.assign(n, 0);
  onStack_.assign(n, 0);
  stop_.assign(n, 0);
  const auto moving = [&](std::size_t a) { return next[a] != now[a]; };
  for (std::size_t a = 0; a < n; ++a) {
    agentAt_[static_cast<std::size_t>(now[a])] = static_cast<std::int32_t>(a);
    if (moving(a)) {
      arrivingAt_[static_cast<std::size_t>(next[a])] = static_cast<std::int32_t>(a);
    }
  }

  // Tarjan's strongly connected components over the follow relation, iteratively (a queue of
  // thousands of robots would overflow a recursive one). Every cycle lies inside one component of
  // two or more agents, so stopping those stops every cycle.
  std::int32_t counter = 0;
  std::size_t stopped = 0;
  stack_.clear();
  frames_.clear();
  for (std::size_t s = 0; s < n; ++s) {
    if (index_[s] >= 0 || !moving(s)) {
      continue;
    }
    index_[s] = low_[s] = counter++;
    stack_.push_back(static_cast<std::int32_t>(s));
    onStack_[s] = 1;
    frames_.emplace_back(static_cast<std::int32_t>(s), 0);
    while (!frames_.empty()) {
      auto& [v, k] = frames_.back();
      const auto vi = static_cast<std::size_t>(v);
      const NodeId w = excluded(next[vi], k);
      if (w != kNoNode) {
        ++k;
        const std::int32_t b = agentAt_[static_cast<std::size_t>(w)];
        if (b < 0 || b == v || !moving(static_cast<std::size_t>(b))) {
          continue;
        }
        const auto bi = static_cast<std::size_t>(b);
        if (index_[bi] < 0) {
          index_[bi] = low_[bi] = counter++;
          stack_.push_back(b);
          onStack_[bi] = 1;
          frames_.emplace_back(b, 0);  // invalidates v and k: re-read at the top of the loop
        } else if (onStack_[bi] != 0) {
          low_[vi] = std::min(low_[vi], index_[bi]);
        }
        continue;
      }
      const std::int32_t done = v;
      frames_.pop_back();
      const auto di = static_cast<std::size_t>(done);
      if (low_[di] == index_[di]) {
        // The component sits on top of the stack; search from there (a long queue of followers
        // would make a search from the bottom quadratic).
        const auto top = stack_.end();
        auto it = top;
        while (*(it - 1) != done) {
          --it;
        }
        --it;
        const bool cycle = top - it > 1;
        for (auto j = it; j != top; ++j) {
          onStack_[static_cast<std::size_t>(*j)] = 0;
          if (cycle) {
            stop_[static_cast<std::size_t>(*j)] = 1;
            queue_.push_back(*j);
            ++stopped;
          }
        }
        stack_.erase(it, top);
      }
      if (!frames_.empty()) {
        const auto pi = static_cast<std::size_t>(frames_.back().first);
        low_[pi] = std::min(low_[pi], low_[di]);
      }
    }
  }

  // Whoever was moving into a node a stopped agent still excludes has to stop too, transitively.
  for (std::size_t q = 0; q < queue_.size(); ++q) {
    const auto b = static_cast<std::size_t>(queue_[q]);
    for (std::size_t k = 0;; ++k) {
      const NodeId w = excluded(now[b], k);
      if (w == kNoNode) {
        break;
      }
      const std::int32_t a = arrivingAt_[static_cast<std::size_t>(w)];
      if (a < 0 || static_cast<std::size_t>(a) == b || stop_[static_cast<std::size_t>(a)] != 0) {
        continue;
      }
      stop_[static_cast<std::size_t>(a)] = 1;
      queue_.push_back(a);
      ++stopped;
    }
  }
  queue_.clear();

  for (std::size_t a = 0; a < n; ++a) {
    agentAt_[static_cast<std::size_t>(now[a])] = -1;
    if (moving(a)) {
      arrivingAt_[static_cast<std::size_t>(next[a])] = -1;
    }
  }
  for (std::size_t a = 0; a < n; ++a) {
    if (stop_[a] != 0) {
      next[a] = now[a];
    }
  }
  return stopped;
}

}  // namespace fleet::traffic
