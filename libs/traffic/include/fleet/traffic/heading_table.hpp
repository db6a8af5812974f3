#pragma once

// Heading tables: what turning adds to a goal's cost-to-go, per edge a robot arrives by.
//
// A goal's DistanceTable knows the least time from each node, as if a robot could leave a node in
// any direction at once (each edge's duration holds only the least turn any way into it). A robot
// arriving at u from t has a heading: leaving u by u→w costs the turn t→u→w on top. Its real
// cost-to-go is h(t→u) = min over u→w of turn(t, u, w) + cost(u→w) + h(u→w), a shortest path over
// the roadmap's edges (its line graph), searched backward from the edges into the goal.
//
// The table keeps that path's *surcharge* over the node table, s(t→u) = h(t→u) − D(u) ≥ 0, with D
// the goal's node distances on the open graph (no node costs, nothing blocked). The planner ranks a
// move from u to v, having come from t, by turn(t, u, v) + D'(v) + s(u→v), and standing by
// D'(u) + s(t→u), where D' is its node table with what changes by the second (people's costs,
// robots out of control): those stay exact and cheap to repair, and the turns come from the
// static graph. A surcharge is recomputed only when the graph changes (invalidate()).
//
// A search costs a few times a node table's (every edge settled, every turn at each node relaxed),
// so it runs in slices: work(budget) goes on with the searches asked for, at most `budget` turns
// relaxed per call, and a goal's surcharge is there (find()) only once its search has finished.
// Until then the planner ranks that goal's moves by the node table alone. Finished tables are
// kept up to a byte budget, least recently used dropped first.

#include <cstdint>
#include <deque>
#include <functional>
#include <span>
#include <unordered_map>
#include <vector>

#include "fleet/traffic/graph.hpp"

namespace fleet::traffic {

class HeadingTable {
 public:
  /// s of turning at `at` between prev→at and at→next beyond what at→next's duration holds
  /// (Roadmap::extraTurn); >= 0.
  using TurnTime = std::function<double(NodeId prev, NodeId at, NodeId next)>;

  HeadingTable(const Graph& graph, TurnTime turn, std::size_t maxBytes = std::size_t{64} << 20);

  /// Directed edge index of `at`'s out-edge number `out` (graph.edges(at)[out]).
  [[nodiscard]] std::size_t outEdge(NodeId at, std::size_t out) const {
    return offset_[static_cast<std::size_t>(at)] + out;
  }
  /// Index of the edge from→to, -1 when there is none.
  [[nodiscard]] std::int64_t edgeBetween(NodeId from, NodeId to) const;
  /// Turning at `at` having arrived by edge `in` (an index) and leaving by out-edge number `out`.
  [[nodiscard]] float turn(std::size_t in, NodeId at, std::size_t out) const;
  [[nodiscard]] std::size_t edges() const { return tail_.size(); }

  /// The goal's surcharge per arriving edge, nullptr until its search has finished (want()).
  /// Valid until the next work(), compute() or invalidate(). Unreachable edges hold 0.
  [[nodiscard]] const float* find(NodeId goal);
  /// The goals wanted now: the searches queued become those of them without a table, in their
  /// order (the search under way is finished first, wanted or not).
  void want(std::span<const NodeId> goals);
  /// Goes on with the queued searches, relaxing at most `budget` turns (at least the rest of one
  /// edge's). Returns the turns relaxed.
  std::size_t work(std::size_t budget);
  /// The whole search of `goal` at once (tests, benchmarks).
  const float* compute(NodeId goal);
  /// The graph changed (opened, closed or grew): every table and search dropped.
  void invalidate();

  [[nodiscard]] std::size_t cached() const { return tables_.size(); }
  [[nodiscard]] std::size_t pending() const { return queue_.size(); }
  [[nodiscard]] std::uint64_t computed() const { return computed_; }

 private:
  struct Table {
    NodeId goal = kNoNode;
    std::vector<float> surcharge;  ///< per edge
    std::uint64_t used = 0;
  };
  void build();
  void start(NodeId goal);
  void finish();

  const Graph& graph_;
  TurnTime turnTime_;
  std::size_t maxBytes_;
  std::size_t maxTables_ = 1;
  std::size_t builtFor_ = 0;            ///< graph size the index was built for
  std::vector<std::size_t> offset_;     ///< per node: its first out-edge's index
  std::vector<NodeId> tail_;            ///< per edge
  std::vector<NodeId> head_;            ///< per edge
  std::vector<float> cost_;             ///< per edge: Edge::cost()
  std::vector<std::uint32_t> inStart_;  ///< per node: its in-edges in in_
  std::vector<std::uint32_t> in_;       ///< edge indices by head
  std::vector<std::uint32_t> inPos_;    ///< per edge: its place among its head's in-edges
  std::vector<std::size_t> pairStart_;  ///< per node: its turns, in-edge major
  std::vector<float> pair_;             ///< turn per (in-edge, out-edge) at each node
  std::vector<Table> tables_;
  std::unordered_map<NodeId, std::size_t> slotOf_;  ///< goal → its table in tables_
  std::uint64_t clock_ = 0;
  std::uint64_t computed_ = 0;
  // The search under way: the goal's node distances, then the edges' cost-to-go.
  std::deque<NodeId> queue_;
  std::vector<std::uint32_t> wanted_;  ///< per node: stamp_ when want() last named it
  std::uint32_t stamp_ = 0;
  NodeId searching_ = kNoNode;
  std::vector<float> node_;
  std::vector<float> h_;
  std::vector<std::pair<float, std::uint32_t>> heap_;
};

}  // namespace fleet::traffic
