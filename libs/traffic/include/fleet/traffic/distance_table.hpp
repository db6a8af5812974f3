#pragma once

// Per-goal distance tables: for a goal g, the shortest time from every node to g along open edges.
// The planner asks for the distance of a handful of nodes to each agent's goal every step; one
// backward search per goal answers all of them, so tables are computed on first use and kept in a
// bounded least-recently-used cache (a lifelong run keeps asking for the same goals: stations,
// shelves). Breadth-first search when every edge lasts the same, Dijkstra otherwise.
//
// Closed nodes and edges are honoured: nothing passes through a closed node, but a robot standing
// on one gets the distance of leaving it (it may drive off, nothing may drive on). After closing or
// reopening anything, or adding nodes or edges, call invalidate(). Nodes blocked by setBlocked()
// (fixed obstacles the graph does not know about) count as closed.
//
// Blocking, unblocking and node costs change often (a robot held for a few seconds, people moving
// through the risk map) while most tables are searched only from the goal as far as they were
// read. Such a change leaves alone the tables whose search has not settled a changed node (it
// never used its cost: its settled distances and its frontier are those of a search started after
// the change) and repairs the others in place: only the distances the change really moves are
// searched again (distance_repair.cpp), every value as exact as a search started afresh. A table
// not read since the change before, and every table a change of more than kRepairMaxChanges nodes
// reaches, is dropped instead and searched again from its goal when next asked for.

#include <cstdint>
#include <limits>
#include <span>
#include <vector>

#include "fleet/traffic/graph.hpp"

namespace fleet::traffic {

/// A backward search to one goal kept open (a goal's table, DistanceTable::distance): a distance is
/// final once its node is settled (DistanceTable::settle), until then an upper bound.
struct PartialTable {
  NodeId goal = kNoNode;
  std::vector<float> dist;                     ///< final where settled, else an upper bound
  std::vector<std::uint64_t> settled;          ///< one bit per node
  std::vector<std::pair<float, NodeId>> heap;  ///< the search's frontier
  std::uint64_t settledCount = 0;
  /// The largest settled distance (infinite once the frontier ran out): every node not settled is
  /// at least this far from the goal, which is what lets a change be repaired in place.
  float radius = 0.0F;

  [[nodiscard]] bool empty() const { return goal == kNoNode; }
  void clear() { goal = kNoNode; }
  /// A search to `goal` over `n` nodes that has settled nothing and has an empty frontier.
  void reset(NodeId g, std::size_t n) {
    goal = g;
    dist.assign(n, std::numeric_limits<float>::infinity());
    settled.assign((n + 63) / 64, 0);
    heap.clear();
    settledCount = 0;
    radius = 0.0F;
  }
  [[nodiscard]] const float* data() const { return dist.data(); }
  [[nodiscard]] bool isSettled(NodeId v) const {
    const auto i = static_cast<std::size_t>(v);
    return ((settled[i >> 6] >> (i & 63)) & 1U) != 0;
  }
};

class DistanceTable {
 public:
  static constexpr float kUnreachable = std::numeric_limits<float>::infinity();
  /// What a change does to a table that has settled a changed node: repaired in place (the
  /// default), or restarted from its goal (the simple reference, kept for tests and benchmarks).
  enum class OnChange : std::uint8_t { kRepair, kRestart };
  /// A change of more nodes than this at once restarts the tables it reaches instead (applyChanges).
  static constexpr std::size_t kRepairMaxChanges = 64;

  /// Keeps at most `maxBytes` of tables (at least one table, and at least reserve()'s count).
  explicit DistanceTable(const Graph& graph, std::size_t maxBytes = std::size_t{256} << 20);

  /// Distances from every node to `goal` (kUnreachable where there is no route, and everywhere when
  /// the goal is closed). The span stays valid until capacity() other goals have been asked for
  /// after it, or invalidate().
  std::span<const float> to(NodeId goal);
  /// The distance of `from` to `goal`, searching the goal's table only as far as `from`.
  float distance(NodeId from, NodeId goal);
  /// The goal's table as far as searched so far: a value is final only where settled by
  /// distance() or settleAround(goal, ...) (or everywhere after to()). Valid as long as to()'s.
  const float* partialTo(NodeId goal);
  /// Settles `v` and every node within `hops` edges of it in the goal's table, if it has one.
  void settleAround(NodeId goal, NodeId v, int hops);

  /// Keep room for at least `tables` goals at once (a planner holding every agent's goal table
  /// through a step needs agents + 1), whatever the byte budget says.
  void reserve(std::size_t tables);
  /// The graph changed (opened or closed something, or grew): drop every table.
  void invalidate();
  /// Treats `v` as closed (or not) on top of the graph: the planner's fixed obstacles (robots out of
  /// its control stand there), except as a goal (the route still leads up to it). Tables are
  /// dropped at the next query when anything changed.
  void setBlocked(NodeId v, bool blocked);
  [[nodiscard]] bool blocked(NodeId v) const { return blocked_[static_cast<std::size_t>(v)] != 0; }

  /// A standing cost (s) of driving into each node, on top of the edges' route costs (their
  /// durations unless the roadmap has flow guidance, Edge::cost), in every table
  /// from the next query on (the traffic manager's collision-probability map: people-dense space
  /// costs more). One entry per node, each finite and >= 0; empty: none. Tables are recomputed
  /// when it changed; searches are then Dijkstra's even on unit grids.
  /// Returns whether it changed.
  bool setNodeCost(std::vector<float> cost);
  [[nodiscard]] std::span<const float> nodeCost() const { return nodeCost_; }

  /// Goes on with `t`'s search (a goal's table or a detour) until `v` is settled; returns its final
  /// distance (kUnreachable when there is no route).
  float settle(PartialTable& t, NodeId v) const;
  /// Settles `v` and every node within `hops` edges of it.
  void settleAround(PartialTable& t, NodeId v, int hops) const;
  /// A detour table round `from` only (local_detour.cpp): the distances to `goal` of the nodes
  /// `from` reaches without going farther than `radius` (m) from it, entering v costing `extra[v]`
  /// more inside, leaving the disc valued at the goal table's distance; every other node
  /// unreachable. Searched whole (a few thousand nodes at most), every node final.
  void detourAround(NodeId goal, NodeId from, double radius, std::span<const float> extra, PartialTable& out);
  [[nodiscard]] std::size_t capacity() const { return capacity_; }
  [[nodiscard]] std::size_t cached() const { return used_; }
  /// Tables computed or restarted since construction (misses), for benchmarks and tests.
  [[nodiscard]] std::uint64_t computed() const { return computed_; }
  /// Tables repaired in place after a change (applyChanges), for benchmarks and tests.
  [[nodiscard]] std::uint64_t repaired() const { return repaired_; }
  void setOnChange(OnChange c) { onChange_ = c; }
  /// true when every edge has the same duration (breadth-first search).
  [[nodiscard]] bool unitDurations() const { return unit_; }

 private:
  void buildReverse();
  /// Entering v in a goal's table: its node cost, infinite when closed or blocked.
  [[nodiscard]] float baseEnter(std::size_t v) const;
  /// Takes in what setBlocked()/setNodeCost() changed since the last query: repairs the tables
  /// that read a changed node (drops everything when a change is too wide to be worth sorting out).
  void applyChanges();
  /// Lists node `v` as changed (or marks the whole table dirty once half the nodes are listed).
  void noteChange(NodeId v);
  /// distance_repair.cpp: the table after raised_'s nodes cost more to enter (the new cost already
  /// in baseEnter_), then after lowered_'s cost less. true when it changed.
  bool repairRaised(PartialTable& t);
  bool repairLowered(PartialTable& t);
  /// The least way from `v` to the goal through the nodes `t` has settled.
  [[nodiscard]] float viaSettled(const PartialTable& t, NodeId v) const;
  /// A whole table by breadth-first search (unit durations, no node cost).
  void compute(NodeId goal, std::vector<float>& d);
  std::size_t acquire(NodeId goal);
  void start(NodeId goal, PartialTable& t) const;
  float settleIn(PartialTable& t, std::span<const float> enterOf, NodeId v) const;
  void settleAroundIn(PartialTable& t, std::span<const float> enterOf, NodeId v, int hops) const;
  std::size_t acquireSlot();
  void touch(std::size_t slot);
  void unlink(std::size_t slot);
  /// baseEnter_ of `nodes` from what is blocked, closed and costed now.
  void takeIn(std::span<const NodeId> nodes);
  /// Forgets the slot's table and makes the slot the next one reused.
  void drop(std::size_t slot);

  const Graph& graph_;
  std::size_t maxBytes_;
  std::size_t capacity_ = 1;
  bool unit_ = true;
  float unitDuration_ = 1.0F;
  // Reverse adjacency (who can drive into v, and how long that takes), compressed rows.
  std::vector<std::uint32_t> revStart_;
  std::vector<NodeId> revFrom_;
  std::vector<float> revDuration_;
  // Cache: slot per goal, slots on an intrusive LRU list (head = most recent).
  std::vector<std::int32_t> slotOfGoal_;
  std::vector<NodeId> goalOfSlot_;
  std::vector<std::uint64_t> readAt_;  ///< per slot, batch_ when its table was last asked for
  std::uint64_t batch_ = 0;            ///< change batches taken in (applyChanges)
  std::vector<PartialTable> tables_;
  std::vector<float> baseEnter_;  ///< entering each node in a goal's table (infinite: closed or blocked)
  std::vector<std::int32_t> prev_;
  std::vector<std::int32_t> next_;
  std::int32_t head_ = -1;
  std::int32_t tail_ = -1;
  std::size_t used_ = 0;
  std::uint64_t computed_ = 0;
  std::uint64_t repaired_ = 0;
  OnChange onChange_ = OnChange::kRepair;
  std::vector<std::uint8_t> blocked_;
  std::vector<float> nodeCost_;
  bool dirty_ = false;
  std::vector<NodeId> changed_;  ///< nodes whose entering cost changed since the last query
  // Repair scratch (distance_repair.cpp): the nodes costing more / less to enter, a mark per node,
  // a list of marked nodes and a heap.
  std::vector<NodeId> raised_;
  std::vector<NodeId> lowered_;
  std::vector<std::uint8_t> mark_;
  std::vector<NodeId> marked_;
  std::vector<NodeId> affected_;
  std::vector<std::pair<float, NodeId>> work_;
  // Search scratch, kept to avoid allocating per table.
  std::vector<NodeId> queue_;
  std::vector<NodeId> region_;          ///< detourAround's disc
  std::vector<std::uint8_t> inRegion_;  ///< per node, 1 while in detourAround's disc
};

}  // namespace fleet::traffic
