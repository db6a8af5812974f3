#pragma once

// Where a new order starts. The specification (2.1, 6.6.3) lets a vehicle take a new order only
// when its first node is where it stands (its last node, or a node whose deviation range it is
// in); a vehicle refuses any other with a noRouteError. The traffic layer's release starts at the
// node it last accepted from the vehicle, which can differ from the vehicle's own last node (a
// progress report it refused, a replan while the vehicle drove on, a cancel between two nodes).
// So a new order is cut or extended to begin at the vehicle's last node: the nodes of the release
// it has passed are dropped, or - when the release begins at a neighbour of that node - the node
// and the edge to the release are put in front. Anything else is refused: no order the vehicle
// would reject is sent.

#include <map>
#include <optional>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "fleet/core/expected.hpp"
#include "fleet/vda5050/order_builder.hpp"

namespace fleet::vda5050 {

/// The roadmap as far as the master control knows it: node positions and the directed edges a
/// vehicle may drive (from the traffic layer's roadmap, and the edges of orders already sent).
class KnownRoadmap {
 public:
  void addNode(const ReleaseNode& n) { nodes_[n.node] = n; }
  void addEdge(int from, int to) { edges_.emplace(from, to); }
  /// Forgets every node and edge (a new roadmap replaces the old one).
  void clear();
  [[nodiscard]] std::optional<ReleaseNode> node(int id) const;
  [[nodiscard]] bool hasEdge(int from, int to) const { return edges_.contains({from, to}); }

 private:
  std::map<int, ReleaseNode> nodes_;
  std::set<std::pair<int, int>> edges_;
};

/// `release` made to start at the vehicle's last node `last_node_id` (an order nodeId, "n12"):
/// cut at that node when its base passes it, or with the node put in front when the base begins
/// at a node the roadmap joins it to. An empty `last_node_id` (a vehicle that never reached a
/// node) takes the release as it is. Refused, naming both nodes, when neither holds.
Expected<ReleaseInput> startAtVehicle(const ReleaseInput& release, const std::string& last_node_id,
                                      const KnownRoadmap& roadmap);

}  // namespace fleet::vda5050
