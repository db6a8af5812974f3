#pragma once

// Orders along a straight line of nodes n0, n1, ... (1 m apart on map "small"), the first
// `released` of them base, for the rule and conversion tests.

#include <string>

#include "fleet/vda5050/order.hpp"

namespace fleet::vda5050::test {

inline Order lineOrder(const std::string& order_id, std::uint32_t update_id, int first, int count,
                       int released) {
  Order o;
  o.header = {1, "2026-11-26T03:00:00.000Z", kVersion, "acme", "AGV-1"};
  o.orderId = order_id;
  o.orderUpdateId = update_id;
  for (int i = 0; i < count; ++i) {
    const int k = first + i;
    Node n;
    n.nodeId = "n" + std::to_string(k);
    n.sequenceId = static_cast<std::uint32_t>(2 * k);
    n.released = i < released;
    n.nodePosition = NodePosition{static_cast<double>(k), 0.0, 0.0, 0.1, {}, "small"};
    o.nodes.push_back(n);
    if (i > 0) {
      Edge e;
      e.edgeId = "e" + std::to_string(k - 1) + "-" + std::to_string(k);
      e.sequenceId = static_cast<std::uint32_t>(2 * k - 1);
      e.released = n.released;
      e.startNodeId = "n" + std::to_string(k - 1);
      e.endNodeId = n.nodeId;
      o.edges.push_back(e);
    }
  }
  return o;
}

}  // namespace fleet::vda5050::test
