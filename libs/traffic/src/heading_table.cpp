// Heading tables (heading_table.hpp): a goal's cost-to-go per arriving edge, turns included, kept
// as a surcharge over the node distances; searched in slices.

#include "fleet/traffic/heading_table.hpp"

#include <algorithm>
#include <limits>

namespace fleet::traffic {

namespace {
constexpr float kInf = std::numeric_limits<float>::infinity();
}  // namespace

HeadingTable::HeadingTable(const Graph& graph, TurnTime turn, std::size_t maxBytes)
    : graph_(graph), turnTime_(std::move(turn)), maxBytes_(maxBytes) {
  invalidate();
}

void HeadingTable::build() {
  const std::size_t n = graph_.size();
  builtFor_ = n;
  offset_.assign(n + 1, 0);
  for (std::size_t u = 0; u < n; ++u) {
    offset_[u + 1] = offset_[u] + graph_.edges(static_cast<NodeId>(u)).size();
  }
  const std::size_t m = offset_.back();
  tail_.resize(m);
  head_.resize(m);
  cost_.resize(m);
  inStart_.assign(n + 1, 0);
  for (std::size_t u = 0; u < n; ++u) {
    const auto es = graph_.edges(static_cast<NodeId>(u));
    for (std::size_t i = 0; i < es.size(); ++i) {
      const std::size_t e = offset_[u] + i;
      tail_[e] = static_cast<NodeId>(u);
      head_[e] = es[i].to;
      cost_[e] = static_cast<float>(es[i].cost());
      ++inStart_[static_cast<std::size_t>(es[i].to) + 1];
    }
  }
  for (std::size_t v = 0; v < n; ++v) {
    inStart_[v + 1] += inStart_[v];
  }
  in_.resize(m);
  inPos_.resize(m);
  std::vector<std::uint32_t> fill(inStart_.begin(), inStart_.end() - 1);
  for (std::size_t e = 0; e < m; ++e) {
    const auto v = static_cast<std::size_t>(head_[e]);
    inPos_[e] = fill[v] - inStart_[v];
    in_[fill[v]++] = static_cast<std::uint32_t>(e);
  }
  pairStart_.assign(n + 1, 0);
  for (std::size_t u = 0; u < n; ++u) {
    pairStart_[u + 1] = pairStart_[u] + (inStart_[u + 1] - inStart_[u]) * (offset_[u + 1] - offset_[u]);
  }
  pair_.assign(pairStart_.back(), 0.0F);
  for (std::size_t u = 0; u < n; ++u) {
    const std::size_t outs = offset_[u + 1] - offset_[u];
    for (std::uint32_t k = inStart_[u]; k < inStart_[u + 1]; ++k) {
      const NodeId t = tail_[in_[k]];
      for (std::size_t j = 0; j < outs; ++j) {
        const double s = turnTime_ ? turnTime_(t, static_cast<NodeId>(u), head_[offset_[u] + j]) : 0.0;
        pair_[pairStart_[u] + (k - inStart_[u]) * outs + j] = static_cast<float>(std::max(0.0, s));
      }
    }
  }
}

std::int64_t HeadingTable::edgeBetween(NodeId from, NodeId to) const {
  if (!graph_.valid(from) || static_cast<std::size_t>(from) >= builtFor_) {
    return -1;
  }
  const auto f = static_cast<std::size_t>(from);
  for (std::size_t e = offset_[f]; e < offset_[f + 1]; ++e) {
    if (head_[e] == to) {
      return static_cast<std::int64_t>(e);
    }
  }
  return -1;
}

float HeadingTable::turn(std::size_t in, NodeId at, std::size_t out) const {
  const auto u = static_cast<std::size_t>(at);
  return pair_[pairStart_[u] + inPos_[in] * (offset_[u + 1] - offset_[u]) + out];
}

const float* HeadingTable::find(NodeId goal) {
  const auto it = slotOf_.find(goal);
  if (it == slotOf_.end()) {
    return nullptr;
  }
  Table& t = tables_[it->second];
  t.used = ++clock_;
  return t.surcharge.data();
}

void HeadingTable::want(std::span<const NodeId> goals) {
  queue_.clear();
  if (++stamp_ == 0) {
    std::fill(wanted_.begin(), wanted_.end(), 0);
    stamp_ = 1;
  }
  wanted_.resize(graph_.size(), 0);
  for (const NodeId g : goals) {
    if (!graph_.valid(g) || wanted_[static_cast<std::size_t>(g)] == stamp_) {
      continue;
    }
    wanted_[static_cast<std::size_t>(g)] = stamp_;
    if (g != searching_ && !slotOf_.contains(g)) {
      queue_.push_back(g);
    }
  }
  // A search under way is finished even when its goal is no longer wanted: given up, its work
  // would be lost, and goals come back (a station, a parking place).
}

void HeadingTable::invalidate() {
  tables_.clear();
  slotOf_.clear();
  queue_.clear();
  searching_ = kNoNode;
  build();  // nodes or edges may have been added, and edge costs changed (flow guidance)
  maxTables_ = std::max<std::size_t>(1, maxBytes_ / std::max<std::size_t>(1, edges() * sizeof(float)));
}

void HeadingTable::start(NodeId goal) {
  searching_ = goal;
  const std::size_t n = graph_.size();
  const auto later = std::greater<>{};
  // The goal's node distances over open nodes and edges, as a DistanceTable without node costs.
  node_.assign(n, kInf);
  node_[static_cast<std::size_t>(goal)] = 0.0F;
  heap_.assign(1, {0.0F, static_cast<std::uint32_t>(goal)});
  while (!heap_.empty()) {
    std::pop_heap(heap_.begin(), heap_.end(), later);
    const auto [d, w] = heap_.back();
    heap_.pop_back();
    if (d != node_[w]) {
      continue;
    }
    for (std::uint32_t k = inStart_[w]; k < inStart_[w + 1]; ++k) {
      const std::uint32_t e = in_[k];
      const NodeId u = tail_[e];
      const auto es = graph_.edges(u);
      if (!graph_.passable(u, es[e - offset_[static_cast<std::size_t>(u)]])) {
        continue;
      }
      const float c = d + cost_[e];
      if (c < node_[static_cast<std::size_t>(u)]) {
        node_[static_cast<std::size_t>(u)] = c;
        heap_.emplace_back(c, static_cast<std::uint32_t>(u));
        std::push_heap(heap_.begin(), heap_.end(), later);
      }
    }
  }
  // Then the edges' cost-to-go, from those into the goal.
  h_.assign(edges(), kInf);
  const auto g = static_cast<std::size_t>(goal);
  for (std::uint32_t k = inStart_[g]; k < inStart_[g + 1]; ++k) {
    h_[in_[k]] = 0.0F;
    heap_.emplace_back(0.0F, in_[k]);
  }
  std::make_heap(heap_.begin(), heap_.end(), later);
}

std::size_t HeadingTable::work(std::size_t budget) {
  std::size_t done = 0;
  const auto later = std::greater<>{};
  while (done < budget) {
    if (searching_ == kNoNode) {
      if (queue_.empty()) {
        break;
      }
      const NodeId goal = queue_.front();
      queue_.pop_front();
      start(goal);
      done += graph_.size() + edges();  // the node distances: every node settled, every edge relaxed
    }
    while (!heap_.empty() && done < budget) {
      std::pop_heap(heap_.begin(), heap_.end(), later);
      const auto [d, e] = heap_.back();
      heap_.pop_back();
      ++done;
      if (d != h_[e]) {
        continue;
      }
      // e = u→w, settled: a robot arriving at u by f = t→u may go on by e.
      const NodeId u = tail_[e];
      const auto uu = static_cast<std::size_t>(u);
      const std::size_t out = e - offset_[uu];
      if (!graph_.passable(u, graph_.edges(u)[out])) {
        continue;
      }
      const std::size_t outs = offset_[uu + 1] - offset_[uu];
      const float via = d + cost_[e];
      for (std::uint32_t k = inStart_[uu]; k < inStart_[uu + 1]; ++k) {
        const std::uint32_t f = in_[k];
        const float c = via + pair_[pairStart_[uu] + (k - inStart_[uu]) * outs + out];
        if (c < h_[f]) {
          h_[f] = c;
          heap_.emplace_back(c, f);
          std::push_heap(heap_.begin(), heap_.end(), later);
        }
      }
      done += inStart_[uu + 1] - inStart_[uu];
    }
    if (heap_.empty()) {
      finish();
    }
  }
  return done;
}

void HeadingTable::finish() {
  Table* slot = nullptr;
  if (tables_.size() < maxTables_) {
    slot = &tables_.emplace_back();
  } else {
    slot = &*std::min_element(tables_.begin(), tables_.end(),
                              [](const Table& a, const Table& b) { return a.used < b.used; });
  }
  if (slot->goal != kNoNode) {
    slotOf_.erase(slot->goal);
  }
  slot->goal = searching_;
  slotOf_[searching_] = static_cast<std::size_t>(slot - tables_.data());
  slot->used = ++clock_;
  slot->surcharge.resize(edges());
  for (std::size_t f = 0; f < edges(); ++f) {
    const float d = node_[static_cast<std::size_t>(head_[f])];
    const float h = h_[f];
    slot->surcharge[f] = (h == kInf || d == kInf) ? 0.0F : std::max(0.0F, h - d);
  }
  ++computed_;
  searching_ = kNoNode;
}

const float* HeadingTable::compute(NodeId goal) {
  if (const float* s = find(goal)) {
    return s;
  }
  if (!graph_.valid(goal)) {
    return nullptr;
  }
  // The search under way first (it is never given up), then the goal's alone: a search queued
  // after it could otherwise evict its table within a small byte budget.
  std::deque<NodeId> queued;
  queued.swap(queue_);
  if (searching_ != goal) {
    queue_.push_back(goal);
  }
  while (find(goal) == nullptr && (searching_ != kNoNode || !queue_.empty())) {
    work(std::numeric_limits<std::size_t>::max());
  }
  for (const NodeId g : queued) {
    if (g != goal) {
      queue_.push_back(g);
    }
  }
  return find(goal);
}

}  // namespace fleet::traffic
