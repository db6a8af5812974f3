#include "fleet/traffic/distance_table.hpp"

#include <algorithm>
#include <functional>

namespace fleet::traffic {

DistanceTable::DistanceTable(const Graph& graph, std::size_t maxBytes) : graph_(graph), maxBytes_(maxBytes) {
  invalidate();
}

void DistanceTable::buildReverse() {
  const std::size_t n = graph_.size();
  revStart_.assign(n + 1, 0);
  unit_ = true;
  bool first = true;
  for (std::size_t a = 0; a < n; ++a) {
    for (const Edge& e : graph_.edges(static_cast<NodeId>(a))) {
      if (!e.open) {
        continue;
      }
      ++revStart_[static_cast<std::size_t>(e.to) + 1];
      const auto d = static_cast<float>(e.cost());
      if (first) {
        unitDuration_ = d;
        first = false;
      } else if (d != unitDuration_) {
        unit_ = false;
      }
    }
  }
  for (std::size_t v = 0; v < n; ++v) {
    revStart_[v + 1] += revStart_[v];
  }
  revFrom_.assign(revStart_[n], kNoNode);
  revDuration_.assign(revStart_[n], 0.0F);
  std::vector<std::uint32_t> fill(revStart_.begin(), revStart_.end() - 1);
  for (std::size_t a = 0; a < n; ++a) {
    for (const Edge& e : graph_.edges(static_cast<NodeId>(a))) {
      if (!e.open) {
        continue;
      }
      const std::uint32_t k = fill[static_cast<std::size_t>(e.to)]++;
      revFrom_[k] = static_cast<NodeId>(a);
      revDuration_[k] = static_cast<float>(e.cost());
    }
  }
}

void DistanceTable::noteChange(NodeId v) {
  // More than half the nodes changed is a start over anyway (applyChanges()): the list stays
  // bounded even when nothing is queried for a long time (a table kept by a core not running).
  if (dirty_)
    return;
  changed_.push_back(v);
  if (changed_.size() > graph_.size() / 2) {
    dirty_ = true;
    changed_.clear();
  }
}

void DistanceTable::setBlocked(NodeId v, bool blocked) {
  auto& b = blocked_[static_cast<std::size_t>(v)];
  if ((b != 0) != blocked) {
    b = blocked ? 1 : 0;
    noteChange(v);
  }
}

bool DistanceTable::setNodeCost(std::vector<float> cost) {
  if (std::all_of(cost.begin(), cost.end(), [](float c) { return c == 0.0F; })) {
    cost.clear();  // all zero is none: unit grids keep their breadth-first search
  }
  if (cost == nodeCost_) {
    return false;
  }
  const std::size_t n = graph_.size();
  const auto at = [n](const std::vector<float>& c, std::size_t v) { return c.size() == n ? c[v] : 0.0F; };
  if ((cost.size() == n || cost.empty()) && (nodeCost_.size() == n || nodeCost_.empty())) {
    for (std::size_t v = 0; v < n; ++v) {
      if (at(cost, v) != at(nodeCost_, v)) {
        noteChange(static_cast<NodeId>(v));
      }
    }
  } else {
    dirty_ = true;  // a table of another size: start over
  }
  nodeCost_ = std::move(cost);
  return true;
}

float DistanceTable::baseEnter(std::size_t v) const {
  const bool open = graph_.isOpen(static_cast<NodeId>(v)) && blocked_[v] == 0;
  return !open ? kUnreachable : nodeCost_.size() == graph_.size() ? nodeCost_[v] : 0.0F;
}

void DistanceTable::applyChanges() {
  if (dirty_ || changed_.size() > graph_.size() / 2) {
    invalidate();
    return;
  }
  // A node blocked and unblocked again since the last query (a replan takes every fixed robot off
  // its node and puts it back) is not a change: only nodes whose entering cost differs count.
  raised_.clear();
  lowered_.clear();
  for (const NodeId w : changed_) {
    const auto v = static_cast<std::size_t>(w);
    const float enter = baseEnter(v);
    if (enter == baseEnter_[v]) {
      continue;  // no change, or a node listed twice and already taken
    }
    (enter > baseEnter_[v] ? raised_ : lowered_).push_back(w);
  }
  changed_.clear();
  if (onChange_ == OnChange::kRestart) {
    takeIn(raised_);
    takeIn(lowered_);
    for (std::size_t slot = 0; slot < used_; ++slot) {
      PartialTable& t = tables_[slot];
      const auto read = [&t](NodeId w) { return t.isSettled(w); };
      if (!t.empty() && (std::any_of(raised_.begin(), raised_.end(), read) ||
                         std::any_of(lowered_.begin(), lowered_.end(), read))) {
        start(t.goal, t);
        ++computed_;
      }
    }
    return;
  }
  // A search that has not settled a changed node has not used its entering cost (it is read when
  // the node is settled and relaxes its predecessors): its settled distances are final for the new
  // costs and its frontier is the one a search started now would have. A table that has is
  // repaired: first for the raised costs alone, then for the lowered ones (each repair needs a
  // table exact for the costs before it) — when it was read since the last change and the change
  // is a few nodes (robots stopping and leaving). One that was not read (a goal nobody drives to
  // any more, kept by the cache) is dropped, to be searched again only if asked for: repairing
  // every cached table on every change cost the full stack's traffic manager ticks of a second at
  // 300 robots, growing with the cache. So is every table a wide change reaches (the risk map's
  // costs moving with 150 people: thousands of nodes, whose repairs took half the traffic
  // manager's time): searched again as far as read, the restart costs less than the repair there.
  const bool few = raised_.size() + lowered_.size() <= kRepairMaxChanges;
  const auto readsAChange = [this](const PartialTable& t) {
    const auto settled = [&t](NodeId w) { return t.isSettled(w); };
    return std::any_of(raised_.begin(), raised_.end(), settled) ||
           std::any_of(lowered_.begin(), lowered_.end(), settled);
  };
  for (std::size_t slot = 0; slot < used_; ++slot) {
    if (!tables_[slot].empty() && (!few || readAt_[slot] != batch_) && readsAChange(tables_[slot])) {
      drop(slot);
    }
  }
  ++batch_;
  if (!few) {
    takeIn(raised_);
    takeIn(lowered_);
    return;
  }
  takeIn(raised_);
  std::vector<std::uint8_t> touched(used_, 0);
  for (std::size_t slot = 0; slot < used_; ++slot) {
    if (!raised_.empty() && !tables_[slot].empty() && repairRaised(tables_[slot])) {
      touched[slot] = 1;
    }
  }
  takeIn(lowered_);
  for (std::size_t slot = 0; slot < used_; ++slot) {
    if (!lowered_.empty() && !tables_[slot].empty() && repairLowered(tables_[slot])) {
      touched[slot] = 1;
    }
    repaired_ += touched[slot];
  }
}

void DistanceTable::takeIn(std::span<const NodeId> nodes) {
  for (const NodeId w : nodes) {
    baseEnter_[static_cast<std::size_t>(w)] = baseEnter(static_cast<std::size_t>(w));
  }
}

void DistanceTable::drop(std::size_t slot) {
  slotOfGoal_[static_cast<std::size_t>(goalOfSlot_[slot])] = -1;
  goalOfSlot_[slot] = kNoNode;
  tables_[slot].clear();
  // Next to be reused: the tail of the least-recently-used list.
  unlink(slot);
  prev_[slot] = tail_;
  next_[slot] = -1;
  if (tail_ >= 0) {
    next_[static_cast<std::size_t>(tail_)] = static_cast<std::int32_t>(slot);
  } else {
    head_ = static_cast<std::int32_t>(slot);
  }
  tail_ = static_cast<std::int32_t>(slot);
}

void DistanceTable::invalidate() {
  dirty_ = false;
  changed_.clear();
  blocked_.resize(graph_.size(), 0);
  buildReverse();
  // Entering each node in a goal's table: its node cost, never when closed or blocked.
  baseEnter_.resize(graph_.size());
  mark_.assign(graph_.size(), 0);
  for (std::size_t v = 0; v < graph_.size(); ++v) {
    baseEnter_[v] = baseEnter(v);
  }
  const std::size_t n = std::max<std::size_t>(graph_.size(), 1);
  const std::size_t byBudget = maxBytes_ / (n * sizeof(float));
  capacity_ = std::max<std::size_t>({byBudget, capacity_, 1});
  slotOfGoal_.assign(graph_.size(), -1);
  goalOfSlot_.clear();
  readAt_.clear();
  tables_.clear();
  prev_.clear();
  next_.clear();
  head_ = tail_ = -1;
  used_ = 0;
}

void DistanceTable::reserve(std::size_t tables) {
  capacity_ = std::max(capacity_, tables);
}

void DistanceTable::unlink(std::size_t slot) {
  if (prev_[slot] >= 0) {
    next_[static_cast<std::size_t>(prev_[slot])] = next_[slot];
  } else {
    head_ = next_[slot];
  }
  if (next_[slot] >= 0) {
    prev_[static_cast<std::size_t>(next_[slot])] = prev_[slot];
  } else {
    tail_ = prev_[slot];
  }
  prev_[slot] = next_[slot] = -1;
}

void DistanceTable::touch(std::size_t slot) {
  const auto s = static_cast<std::int32_t>(slot);
  if (head_ == s) {
    return;
  }
  if (prev_[slot] >= 0 || next_[slot] >= 0 || tail_ == s) {
    unlink(slot);
  }
  next_[slot] = head_;
  prev_[slot] = -1;
  if (head_ >= 0) {
    prev_[static_cast<std::size_t>(head_)] = s;
  }
  head_ = s;
  if (tail_ < 0) {
    tail_ = s;
  }
}

std::size_t DistanceTable::acquireSlot() {
  if (used_ < capacity_) {
    // Slots are created on demand, so a short run never pays for the whole budget.
    if (used_ == tables_.size()) {
      tables_.emplace_back();
      goalOfSlot_.push_back(kNoNode);
      readAt_.push_back(0);
      prev_.push_back(-1);
      next_.push_back(-1);
    }
    return used_++;
  }
  const auto slot = static_cast<std::size_t>(tail_);
  unlink(slot);
  if (goalOfSlot_[slot] != kNoNode) {
    slotOfGoal_[static_cast<std::size_t>(goalOfSlot_[slot])] = -1;
  }
  return slot;
}

std::size_t DistanceTable::acquire(NodeId goal) {
  if (dirty_ || !changed_.empty()) {
    applyChanges();
  }
  const auto g = static_cast<std::size_t>(goal);
  std::int32_t slot = slotOfGoal_[g];
  if (slot < 0) {
    const std::size_t s = acquireSlot();
    start(goal, tables_[s]);
    goalOfSlot_[s] = goal;
    slot = static_cast<std::int32_t>(s);
    slotOfGoal_[g] = slot;
    ++computed_;
  }
  touch(static_cast<std::size_t>(slot));
  readAt_[static_cast<std::size_t>(slot)] = batch_;
  return static_cast<std::size_t>(slot);
}

std::span<const float> DistanceTable::to(NodeId goal) {
  PartialTable& t = tables_[acquire(goal)];
  if (t.settledCount == 0 && unit_ && nodeCost_.empty() && !t.heap.empty()) {
    compute(goal, t.dist);  // a whole table at once: breadth-first when every edge lasts the same
    t.heap.clear();
    std::fill(t.settled.begin(), t.settled.end(), ~std::uint64_t{0});
    t.settledCount = graph_.size();
    t.radius = kUnreachable;
  }
  settleIn(t, baseEnter_, kNoNode);
  return t.dist;
}

const float* DistanceTable::partialTo(NodeId goal) {
  return tables_[acquire(goal)].data();
}

float DistanceTable::distance(NodeId from, NodeId goal) {
  return settleIn(tables_[acquire(goal)], baseEnter_, from);
}

void DistanceTable::settleAround(NodeId goal, NodeId v, int hops) {
  const std::int32_t slot = slotOfGoal_[static_cast<std::size_t>(goal)];
  if (slot >= 0) {
    settleAroundIn(tables_[static_cast<std::size_t>(slot)], baseEnter_, v, hops);
  }
}

void DistanceTable::start(NodeId goal, PartialTable& t) const {
  t.reset(goal, graph_.size());
  // A closed goal is not reachable at all (an empty frontier); a blocked one is where the route
  // leads: the way up to it is what an agent waiting for it needs.
  if (graph_.isOpen(goal)) {
    t.dist[static_cast<std::size_t>(goal)] = 0.0F;
    t.heap.emplace_back(0.0F, goal);
  }
}

void DistanceTable::compute(NodeId goal, std::vector<float>& d) {
  d.assign(graph_.size(), kUnreachable);
  const auto open = [&](NodeId v) { return graph_.isOpen(v) && blocked_[static_cast<std::size_t>(v)] == 0; };
  // A blocked goal (a robot stands there) is still where the route leads: the way up to it is what
  // an agent waiting for it needs. A closed one is not reachable at all.
  if (!graph_.isOpen(goal)) {
    return;
  }
  d[static_cast<std::size_t>(goal)] = 0.0F;
  // Breadth-first: every edge lasts the same and no node costs more (to()).
  queue_.clear();
  queue_.push_back(goal);
  for (std::size_t head = 0; head < queue_.size(); ++head) {
    const NodeId u = queue_[head];
    const float du = d[static_cast<std::size_t>(u)] + unitDuration_;
    for (std::uint32_t k = revStart_[static_cast<std::size_t>(u)];
         k < revStart_[static_cast<std::size_t>(u) + 1]; ++k) {
      const NodeId p = revFrom_[k];
      auto& dp = d[static_cast<std::size_t>(p)];
      if (dp != kUnreachable) {
        continue;
      }
      dp = du;
      // A closed node learns how far it is from the goal (a robot on it may drive off) but
      // routes never pass through it.
      if (open(p)) {
        queue_.push_back(p);
      }
    }
  }
}

}  // namespace fleet::traffic
