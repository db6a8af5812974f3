#pragma once

// How a vehicle says no to an order: the order is not taken (its state keeps the previous orderId
// or orderUpdateId) and an error of one of the order kinds of the specification (2.1, 6.10.6:
// validationError, orderError, orderUpdateError, noRouteError) appears in its state, naming the
// order in errorReferences ("orderId", "orderUpdateId"). Both references are optional in the
// specification; an error that names no order, or another one, is not taken as this order's
// rejection (a vehicle keeps old errors in its state until it takes an order).

#include <cstdint>
#include <optional>
#include <string>

#include "fleet/vda5050/state.hpp"

namespace fleet::vda5050 {

/// validationError, orderError, orderUpdateError or noRouteError.
bool isOrderErrorType(const std::string& error_type);

struct OrderRejection {
  std::string errorType;
  std::string description;  // the vehicle's errorDescription, or a note that it gave none
};

/// The error in `state` by which the vehicle rejected update `update_id` of order `order_id`:
/// an order error naming that orderId and either that orderUpdateId or none. nullopt when there
/// is none or the vehicle has taken that update after all.
std::optional<OrderRejection> findOrderRejection(const State& state, const std::string& order_id,
                                                 std::uint32_t update_id);

}  // namespace fleet::vda5050
