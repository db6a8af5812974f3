#pragma once

// Safe intervals on a roadmap (Phillips and Likhachev, "SIPP: Safe Interval Path Planning for
// Dynamic Environments", ICRA 2011), for robots whose nodes exclude others (graph.hpp).
//
// A timed path says when its robot starts driving into each node and when it arrives there. A
// robot occupies a node from the moment it starts driving into it until it has arrived at the next
// one (while it drives an edge it is somewhere between its two nodes, and its footprint may cover
// either), and it excludes every node that node conflicts with for that time. Those are the node's
// unsafe times for every other robot; a safe interval is a maximal time span between them. Two
// robots that keep to each other's safe intervals never stand on, or drive between, conflicting
// nodes at once — the roadmap's one rule, now in time instead of in synchronous steps. Touching
// ends are allowed: a robot may start into a node at the instant the last occupant has arrived at
// its next one.

#include <cstdint>
#include <limits>
#include <span>
#include <vector>

#include "fleet/traffic/graph.hpp"

namespace fleet::traffic {

inline constexpr double kForever = std::numeric_limits<double>::infinity();

/// A time span [from, to] in s (to may be kForever).
struct Interval {
  double from = 0.0;
  double to = kForever;
};

/// One node of a timed path: the robot starts driving into `node` at `enter` (its arrival time at
/// the path's first node), arrives at `arrive` and starts driving to the next node at `leave`
/// (turning on the spot, if it must, between `arrive` and `leave`). The last node's `leave` is
/// when the robot may be expected to go on from there (kForever: it stays).
struct TimedNode {
  NodeId node = kNoNode;
  double enter = 0.0;
  double arrive = 0.0;
  double leave = kForever;
};
using TimedPath = std::vector<TimedNode>;

/// The span each node of `path` is occupied: from entering it to arriving at the next one (the
/// last: to its `leave`).
std::vector<Interval> occupancy(std::span<const TimedNode> path);

/// The unsafe times of every node: what the robots planned so far occupy, spread over the nodes
/// each occupied node excludes. Each reservation has an owner (a robot's index, or kNobody), so a
/// robot's reservations can be taken back when it is planned again.
class ReservationTable {
 public:
  static constexpr std::int32_t kNobody = -1;

  explicit ReservationTable(const Graph& graph);

  /// A robot occupies `v` over `span`: v and every node it conflicts with become unsafe then.
  void reserve(NodeId v, Interval span, std::int32_t owner = kNobody);
  /// Every node of the path over its occupancy(), up to `until` (later times stay free: a window).
  void reserve(std::span<const TimedNode> path, double until = kForever, std::int32_t owner = kNobody);
  /// Takes back every reservation `owner` made (not kNobody's).
  void release(std::int32_t owner);
  void clear();

  /// The node's unsafe spans, merged where they overlap or touch, in time order.
  [[nodiscard]] std::vector<Interval> unsafe(NodeId v) const;
  /// The node's safe intervals from `from` on, in time order (the complement of unsafe()).
  [[nodiscard]] std::vector<Interval> safe(NodeId v, double from = 0.0) const;
  /// The same into `out` (cleared first; its storage reused: a search asks for many nodes).
  void safe(NodeId v, double from, std::vector<Interval>& out) const;
  /// Whether the node is safe over the whole of [a, b].
  [[nodiscard]] bool safeOver(NodeId v, double a, double b) const;
  /// The first path node (index) and time at which `path` enters what the table holds unsafe, or
  /// -1 when it keeps to the safe intervals throughout.
  [[nodiscard]] std::int64_t firstConflict(std::span<const TimedNode> path) const;

 private:
  struct Span {
    double from;
    double to;
    std::int32_t owner;
  };
  void add(NodeId v, Span span);

  const Graph& graph_;
  std::vector<std::vector<Span>> unsafe_;          ///< per node, by start
  std::vector<NodeId> touched_;                    ///< nodes with unsafe spans (clear() resets only those)
  std::vector<std::vector<NodeId>> ownerTouched_;  ///< per owner: the nodes it reserved
};

}  // namespace fleet::traffic
