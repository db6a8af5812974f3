// A goal's table repaired in place after some nodes' entering costs changed (applyChanges).
//
// A robot dwelling at a dock blocks the nodes its footprint covers, and unblocks them when it
// leaves. Restarting every table that had settled one of them cost the traffic manager most of its
// worst updates at 300 robots (a third of the run in the search, docs/algorithms.md): each restart
// searched again from the goal as far as the readers stand, though a block moves the distances of
// a few nodes behind it only. The repair searches those again and nothing else, in the manner of
// Ramalingam and Reps' dynamic shortest paths, kept to a table searched part of the way:
//
// - The table's invariant: a settled node holds its final distance, every settled distance is at
//   most the table's radius, every node not settled is at least the radius from the goal, and a
//   node on the frontier holds the least way through the settled nodes (or more, never less than
//   its distance).
// - Raised costs (a block): a settled node keeps its distance when one of its shortest ways, seen
//   from its settled successors, avoids the raised nodes and the nodes that lost theirs. Those that
//   lost theirs (the affected nodes, found in order of distance) are searched again from the nodes
//   that kept theirs, settled again where their new distance is within the radius and left on the
//   frontier where it is not (a way through nodes not settled costs at least the radius). Their
//   predecessors not settled take the least way through what is settled now.
// - Lowered costs (a node unblocked): the ways through the lowered nodes spread back from them as
//   long as they are shorter than what a node holds; a node they reach within the radius gets its
//   final distance (settled), one beyond it is left on the frontier with the shorter value.
//
// Every value is the one a search started afresh gives, to the bit: a node's distance is the least
// of (successor's distance + edge + entering cost) over its successors, computed by the same float
// expression, and that equation has one solution. distance_table_test.cpp checks it against fresh
// tables after random changes.

#include <algorithm>
#include <functional>

#include "fleet/traffic/distance_table.hpp"

namespace fleet::traffic {

namespace {

constexpr std::uint8_t kRaised = 1;
constexpr std::uint8_t kAffected = 2;
constexpr std::uint8_t kSeen = 4;

void markSettled(PartialTable& t, std::size_t v) {
  t.settled[v >> 6] |= std::uint64_t{1} << (v & 63);
  ++t.settledCount;
}

void markUnsettled(PartialTable& t, std::size_t v) {
  t.settled[v >> 6] &= ~(std::uint64_t{1} << (v & 63));
  --t.settledCount;
}

}  // namespace

float DistanceTable::viaSettled(const PartialTable& t, NodeId v) const {
  float best = v == t.goal ? 0.0F : kUnreachable;
  for (const Edge& e : graph_.edges(v)) {
    const auto u = static_cast<std::size_t>(e.to);
    if (!e.open || !t.isSettled(e.to)) {
      continue;
    }
    const float enter = e.to == t.goal ? 0.0F : baseEnter_[u];
    if (enter != kUnreachable && t.dist[u] != kUnreachable) {
      best = std::min(best, t.dist[u] + static_cast<float>(e.cost()) + enter);
    }
  }
  return best;
}

bool DistanceTable::repairRaised(PartialTable& t) {
  const auto later = std::greater<>{};
  auto& work = work_;
  work.clear();
  marked_.clear();
  const auto mark = [&](NodeId v, std::uint8_t bit) {
    auto& m = mark_[static_cast<std::size_t>(v)];
    if (m == 0) {
      marked_.push_back(v);
    }
    m |= bit;
  };
  const auto pushSettledPredecessors = [&](NodeId w) {
    const auto u = static_cast<std::size_t>(w);
    for (std::uint32_t k = revStart_[u]; k < revStart_[u + 1]; ++k) {
      const NodeId p = revFrom_[k];
      if (t.isSettled(p) && (mark_[static_cast<std::size_t>(p)] & kSeen) == 0) {
        mark(p, kSeen);
        work.emplace_back(t.dist[static_cast<std::size_t>(p)], p);
        std::push_heap(work.begin(), work.end(), later);
      }
    }
  };
  bool any = false;
  for (const NodeId w : raised_) {
    if (w != t.goal && t.isSettled(w)) {
      mark(w, kRaised);
      any = true;
    }
  }
  if (!any) {
    for (const NodeId v : marked_) {
      mark_[static_cast<std::size_t>(v)] = 0;
    }
    return false;
  }
  for (const NodeId w : raised_) {
    if ((mark_[static_cast<std::size_t>(w)] & kRaised) != 0) {
      pushSettledPredecessors(w);
    }
  }
  // The affected nodes, nearest the goal first: a node's shortest ways lead to nodes nearer the
  // goal (every edge takes time), whose fate is known by the time it is looked at.
  affected_.clear();
  while (!work.empty()) {
    std::pop_heap(work.begin(), work.end(), later);
    const auto [dp, p] = work.back();
    work.pop_back();
    bool kept = p == t.goal;
    for (const Edge& e : graph_.edges(p)) {
      const auto u = static_cast<std::size_t>(e.to);
      if (!e.open || !t.isSettled(e.to) || (mark_[u] & (kRaised | kAffected)) != 0) {
        continue;
      }
      const float enter = e.to == t.goal ? 0.0F : baseEnter_[u];  // unchanged: not raised
      if (enter != kUnreachable && t.dist[u] + static_cast<float>(e.cost()) + enter == dp) {
        kept = true;
        break;
      }
    }
    if (!kept) {
      mark(p, kAffected);
      affected_.push_back(p);
      pushSettledPredecessors(p);
    }
  }
  // Searched again from the nodes that kept their distance.
  for (const NodeId a : affected_) {
    markUnsettled(t, static_cast<std::size_t>(a));
  }
  for (const NodeId a : affected_) {
    const float d = viaSettled(t, a);
    t.dist[static_cast<std::size_t>(a)] = d;
    if (d != kUnreachable) {
      work.emplace_back(d, a);
    }
  }
  std::make_heap(work.begin(), work.end(), later);
  while (!work.empty()) {
    std::pop_heap(work.begin(), work.end(), later);
    const auto [da, a] = work.back();
    work.pop_back();
    const auto ai = static_cast<std::size_t>(a);
    if (da != t.dist[ai] || t.isSettled(a)) {
      continue;
    }
    if (da > t.radius) {
      // Beyond the radius a way through nodes not settled may be shorter: the rest is frontier.
      t.heap.emplace_back(da, a);
      std::push_heap(t.heap.begin(), t.heap.end(), later);
      continue;
    }
    markSettled(t, ai);
    const float enter = baseEnter_[ai];
    if (enter == kUnreachable) {
      continue;
    }
    for (std::uint32_t k = revStart_[ai]; k < revStart_[ai + 1]; ++k) {
      const NodeId p = revFrom_[k];
      const auto pi = static_cast<std::size_t>(p);
      const float nd = da + revDuration_[k] + enter;
      if ((mark_[pi] & kAffected) != 0 && !t.isSettled(p) && nd < t.dist[pi]) {
        t.dist[pi] = nd;
        work.emplace_back(nd, p);
        std::push_heap(work.begin(), work.end(), later);
      }
    }
  }
  // Predecessors not settled of what changed may hold a way through it that is gone.
  const auto refresh = [&](NodeId w) {
    const auto u = static_cast<std::size_t>(w);
    for (std::uint32_t k = revStart_[u]; k < revStart_[u + 1]; ++k) {
      const NodeId q = revFrom_[k];
      const auto qi = static_cast<std::size_t>(q);
      if (t.isSettled(q) || (mark_[qi] & kAffected) != 0) {
        continue;
      }
      const float d = viaSettled(t, q);
      if (d != t.dist[qi]) {
        t.dist[qi] = d;
        if (d != kUnreachable) {
          t.heap.emplace_back(d, q);
          std::push_heap(t.heap.begin(), t.heap.end(), later);
        }
      }
    }
  };
  for (const NodeId w : raised_) {
    if ((mark_[static_cast<std::size_t>(w)] & kRaised) != 0) {
      refresh(w);
    }
  }
  for (const NodeId a : affected_) {
    refresh(a);
  }
  for (const NodeId v : marked_) {
    mark_[static_cast<std::size_t>(v)] = 0;
  }
  return true;
}

bool DistanceTable::repairLowered(PartialTable& t) {
  const auto later = std::greater<>{};
  auto& work = work_;
  work.clear();
  const auto spread = [&](std::size_t u, float du) {
    const float enter = static_cast<NodeId>(u) == t.goal ? 0.0F : baseEnter_[u];
    if (enter == kUnreachable || du == kUnreachable) {
      return;
    }
    for (std::uint32_t k = revStart_[u]; k < revStart_[u + 1]; ++k) {
      const NodeId p = revFrom_[k];
      const float nd = du + revDuration_[k] + enter;
      if (nd < t.dist[static_cast<std::size_t>(p)]) {
        work.emplace_back(nd, p);
        std::push_heap(work.begin(), work.end(), later);
      }
    }
  };
  bool any = false;
  for (const NodeId w : lowered_) {
    if (w != t.goal && t.isSettled(w)) {
      any = true;
      spread(static_cast<std::size_t>(w), t.dist[static_cast<std::size_t>(w)]);
    }
  }
  while (!work.empty()) {
    std::pop_heap(work.begin(), work.end(), later);
    const auto [dx, x] = work.back();
    work.pop_back();
    const auto xi = static_cast<std::size_t>(x);
    if (dx >= t.dist[xi]) {
      continue;
    }
    t.dist[xi] = dx;
    if (!t.isSettled(x)) {
      if (dx > t.radius) {
        t.heap.emplace_back(dx, x);  // shorter, but beyond the radius: the search goes on from it
        std::push_heap(t.heap.begin(), t.heap.end(), later);
        continue;
      }
      markSettled(t, xi);
    }
    spread(xi, dx);
  }
  return any;
}

}  // namespace fleet::traffic
