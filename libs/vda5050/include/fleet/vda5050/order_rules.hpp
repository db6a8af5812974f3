#pragma once

// The order rules of the specification (2.1, sections 6.6.3 to 6.6.4) as pure functions, used by
// the simulated vehicle to accept or reject an order and by tests to check the bridge's orders:
//  - an order is a chain node, edge, node, ... with even node and odd edge sequenceIds counting up
//    by one, each edge joining its neighbours, and the released base before the horizon;
//  - a new orderId is accepted only when the vehicle has finished or cancelled its order, and must
//    start where the vehicle stands;
//  - an update (same orderId, higher orderUpdateId) must start at the last base node of the
//    current order (same nodeId and sequenceId): it is stitched there, replacing the horizon;
//  - an update with the current orderUpdateId is a duplicate and discarded, a lower one refused.

#include <cstdint>
#include <optional>
#include <string>

#include "fleet/core/expected.hpp"
#include "fleet/vda5050/order.hpp"

namespace fleet::vda5050 {

/// Structural checks of one order message; the error names the offending element.
Expected<void> validateOrder(const Order& order);

/// Where the vehicle stands with its current order.
struct OrderProgress {
  std::string orderId;  // empty: never had an order
  std::uint32_t orderUpdateId = 0;
  std::string lastNodeId;  // the node the vehicle last passed or stands on
  std::uint32_t lastNodeSequenceId = 0;
  std::string baseEndNodeId;  // the last released node of the current order
  std::uint32_t baseEndSequenceId = 0;
  bool active = false;  // nodes left to drive or actions not finished
};

enum class OrderDecision { kAcceptNew, kAcceptUpdate, kDiscardDuplicate, kReject };

struct OrderVerdict {
  OrderDecision decision = OrderDecision::kReject;
  std::string errorType;  // validationError, orderError or orderUpdateError when rejected
  std::string description;
};

/// What the vehicle does with `order` given its `progress` (validateOrder included).
OrderVerdict judgeOrder(const OrderProgress& progress, const Order& order);

/// The current order with `update` stitched at its base end: the current horizon is dropped and
/// the update's nodes and edges follow; the stitching node takes the update's actions too.
/// Precondition: judgeOrder said kAcceptUpdate.
Order stitchOrder(const Order& current, const Order& update);

/// The last released node of an order, if any.
std::optional<Node> baseEnd(const Order& order);

}  // namespace fleet::vda5050
