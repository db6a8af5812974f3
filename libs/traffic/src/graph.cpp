#include "fleet/traffic/graph.hpp"

#include <algorithm>
#include <stdexcept>

namespace fleet::traffic {

NodeId Graph::addNode(Vec2 position) {
  position_.push_back(position);
  edges_.emplace_back();
  conflicts_.emplace_back();
  open_.push_back(1);
  return static_cast<NodeId>(position_.size() - 1);
}

void Graph::addEdge(NodeId a, NodeId b, double duration) {
  if (!valid(a) || !valid(b) || a == b)
    throw std::invalid_argument("Graph::addEdge: bad nodes");
  auto& out = edges_[static_cast<std::size_t>(a)];
  for (auto& e : out) {
    if (e.to == b) {
      e.duration = duration;
      return;
    }
  }
  out.push_back(Edge{b, duration, true, 1.0F});
}

void Graph::addConflict(NodeId a, NodeId b) {
  if (!valid(a) || !valid(b))
    throw std::invalid_argument("Graph::addConflict: bad nodes");
  if (a == b)
    return;
  auto insert = [](std::vector<NodeId>& v, NodeId x) {
    auto it = std::lower_bound(v.begin(), v.end(), x);
    if (it != v.end() && *it == x)
      return false;
    v.insert(it, x);
    return true;
  };
  if (insert(conflicts_[static_cast<std::size_t>(a)], b))
    ++conflictCount_;
  insert(conflicts_[static_cast<std::size_t>(b)], a);
}

bool Graph::conflicting(NodeId a, NodeId b) const {
  if (a == b)
    return true;
  const auto c = conflicts(a);
  return std::binary_search(c.begin(), c.end(), b);
}

Edge* Graph::findEdge(NodeId a, NodeId b) {
  if (!valid(a))
    return nullptr;
  for (auto& e : edges_[static_cast<std::size_t>(a)]) {
    if (e.to == b)
      return &e;
  }
  return nullptr;
}

bool Graph::setEdgeOpen(NodeId a, NodeId b, bool open) {
  Edge* e = findEdge(a, b);
  if (e != nullptr)
    e->open = open;
  return e != nullptr;
}

bool Graph::setEdgeGuide(NodeId a, NodeId b, float guide) {
  Edge* e = guide >= 1.0F ? findEdge(a, b) : nullptr;
  if (e != nullptr)
    e->guide = guide;
  return e != nullptr;
}

const Edge* Graph::edge(NodeId a, NodeId b) const {
  if (!valid(a))
    return nullptr;
  for (const auto& e : edges(a)) {
    if (e.to == b && e.open)
      return &e;
  }
  return nullptr;
}

}  // namespace fleet::traffic
