#include "fleet/vda5050/order_rejection.hpp"

#include <charconv>

namespace fleet::vda5050 {

namespace {

std::optional<std::string> reference(const VehicleError& e, const char* key) {
  for (const auto& [k, v] : e.errorReferences) {
    if (k == key) {
      return v;
    }
  }
  return std::nullopt;
}

}  // namespace

bool isOrderErrorType(const std::string& error_type) {
  return error_type == "validationError" || error_type == "orderError" || error_type == "orderUpdateError" ||
         error_type == "noRouteError";
}

std::optional<OrderRejection> findOrderRejection(const State& state, const std::string& order_id,
                                                 std::uint32_t update_id) {
  if (order_id.empty()) {
    return std::nullopt;
  }
  if (state.orderId == order_id && state.orderUpdateId >= update_id) {
    return std::nullopt;  // taken: an error about it is older than that
  }
  for (const auto& e : state.errors) {
    if (!isOrderErrorType(e.errorType) || reference(e, "orderId") != order_id) {
      continue;
    }
    if (const auto u = reference(e, "orderUpdateId")) {
      std::uint32_t named = 0;
      const auto* end = u->data() + u->size();
      const auto r = std::from_chars(u->data(), end, named);
      if (r.ec != std::errc() || r.ptr != end || named != update_id) {
        continue;  // another update of the order (or a reference we cannot read)
      }
    }
    return OrderRejection{e.errorType, e.errorDescription.value_or("(no errorDescription)")};
  }
  return std::nullopt;
}

}  // namespace fleet::vda5050
