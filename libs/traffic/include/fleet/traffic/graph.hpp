#pragma once

// The graph every traffic piece works on: nodes a robot can stand at, directed edges it can drive,
// and for every node the other nodes a robot standing there excludes. On a MovingAI grid a node
// excludes only itself (the MAPF convention); on a roadmap built from a site the exclusion comes from
// the robot's footprint plus the stop rule's gap (roadmap.hpp), so "no two robots on conflicting
// nodes" is the one rule that keeps them apart, whatever the layout.

#include <cstdint>
#include <span>
#include <vector>

#include "fleet/core/vec2.hpp"

namespace fleet::traffic {

using NodeId = std::int32_t;
inline constexpr NodeId kNoNode = -1;

struct Edge {
  NodeId to = kNoNode;
  double duration = 1.0;  ///< s on a roadmap (drive plus turn), 1 step on a grid
  bool open = true;
  /// What choosing this edge costs a route, as a multiple of its duration (>= 1): the guidance
  /// (guidance.hpp) makes driving against the site's usual flow dearer. Routes and distance tables
  /// use cost(); timing (releases, the robot's motion) uses duration.
  float guide = 1.0F;
  [[nodiscard]] double cost() const { return duration * static_cast<double>(guide); }
};

class Graph {
 public:
  NodeId addNode(Vec2 position);
  /// A directed edge a→b; a two-way lane is two edges. Adding an existing edge updates its duration.
  void addEdge(NodeId a, NodeId b, double duration = 1.0);
  /// a and b exclude each other (symmetric). A node always excludes itself; that is not stored.
  void addConflict(NodeId a, NodeId b);

  [[nodiscard]] std::size_t size() const { return position_.size(); }
  [[nodiscard]] bool valid(NodeId v) const { return v >= 0 && static_cast<std::size_t>(v) < size(); }
  [[nodiscard]] Vec2 position(NodeId v) const { return position_[static_cast<std::size_t>(v)]; }
  /// Out-edges of v, closed ones included (check Edge::open and isOpen(to)).
  [[nodiscard]] std::span<const Edge> edges(NodeId v) const { return edges_[static_cast<std::size_t>(v)]; }
  /// The nodes other than v that a robot at v excludes, sorted.
  [[nodiscard]] std::span<const NodeId> conflicts(NodeId v) const {
    return conflicts_[static_cast<std::size_t>(v)];
  }
  [[nodiscard]] bool conflicting(NodeId a, NodeId b) const;
  /// true when any node excludes another besides itself (a roadmap); false on a plain grid.
  [[nodiscard]] bool hasConflicts() const { return conflictCount_ > 0; }

  /// Closing a node or an edge takes it out of every route until it is reopened; robots already on
  /// it are the planner's business, not the graph's.
  void setOpen(NodeId v, bool open) { open_[static_cast<std::size_t>(v)] = open ? 1 : 0; }
  [[nodiscard]] bool isOpen(NodeId v) const { return open_[static_cast<std::size_t>(v)] != 0; }
  /// false when there is no edge a→b.
  bool setEdgeOpen(NodeId a, NodeId b, bool open);
  /// Sets Edge::guide of a→b (>= 1); false when there is no edge a→b.
  bool setEdgeGuide(NodeId a, NodeId b, float guide);
  /// The open edge a→b, or nullptr.
  [[nodiscard]] const Edge* edge(NodeId a, NodeId b) const;
  /// An open edge from an open node to an open node.
  [[nodiscard]] bool passable(NodeId a, const Edge& e) const { return e.open && isOpen(a) && isOpen(e.to); }

 private:
  Edge* findEdge(NodeId a, NodeId b);  ///< a→b, open or not; nullptr when there is none

  std::vector<Vec2> position_;
  std::vector<std::vector<Edge>> edges_;
  std::vector<std::vector<NodeId>> conflicts_;
  std::vector<std::uint8_t> open_;
  std::size_t conflictCount_ = 0;
};

}  // namespace fleet::traffic
