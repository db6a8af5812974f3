#pragma once

// The master control's side of the order rules: turns the traffic layer's releases for one vehicle
// (base = released roadmap nodes from where the vehicle last reported, horizon = planned nodes)
// into VDA 5050 orders. The first release of a task becomes a new order; each later release
// becomes an update that starts at the current base end with orderUpdateId + 1, or nothing when
// it adds nothing. A release that cannot be stitched (its base does not run through the current
// base end) is refused: the bridge must cancel the order and start a new one.

#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "fleet/core/expected.hpp"
#include "fleet/vda5050/order.hpp"

namespace fleet::vda5050 {

struct ReleaseNode {
  int node = -1;  // roadmap node index
  double x = 0.0;
  double y = 0.0;
};

struct ReleaseInput {
  std::vector<ReleaseNode> base;     // base[0]: the node the vehicle last reported
  std::vector<ReleaseNode> horizon;  // planned after the base, may change
  /// Node actions by roadmap node (pick at the pick-up station, drop at the drop-off), attached
  /// the first time the node is sent.
  std::vector<std::pair<int, Action>> actions;
};

struct OrderBuilderOptions {
  std::string manufacturer;
  std::string serial;
  std::string mapId;
  double allowedDeviationXY = 0.2;
};

class OrderBuilder {
 public:
  explicit OrderBuilder(OrderBuilderOptions options) : options_(std::move(options)) {}

  /// A new order `order_id` from this release (the previous one must be finished or cancelled).
  Expected<Order> start(const std::string& order_id, const ReleaseInput& release, std::int64_t stamp_ns);
  /// The update this release makes to the current order, nullopt when it adds nothing new.
  /// `last_sequence_id` is the vehicle's lastNodeSequenceId from its state.
  Expected<std::optional<Order>> extend(const ReleaseInput& release, std::uint32_t last_sequence_id,
                                        std::int64_t stamp_ns);

  /// The vehicle rejected the updates after `update_id` (it drives on with that one): forget what
  /// they added, so that the next extend starts again at that update's base end. orderUpdateIds
  /// keep counting up, so the next update cannot be taken for one the vehicle rejected. False
  /// when `update_id` was not sent in this order.
  bool rollbackTo(std::uint32_t update_id);

  [[nodiscard]] const std::string& orderId() const { return order_id_; }
  [[nodiscard]] std::uint32_t orderUpdateId() const { return update_id_; }
  /// The roadmap node of an order nodeId ("n12" -> 12), or -1 when it is not one of ours.
  static int roadmapNode(const std::string& node_id);

 private:
  Node makeNode(const ReleaseNode& n, std::uint32_t seq, bool released, const ReleaseInput& release);
  Order assemble(std::vector<Node> nodes, std::int64_t stamp_ns);

  OrderBuilderOptions options_;
  std::string order_id_;
  std::uint32_t update_id_ = 0;
  std::uint32_t header_id_ = 0;
  std::vector<Node> base_;                 // every base node sent in this order, in sequence
  std::vector<std::string> sent_actions_;  // action ids sent in this order (each goes once)
  struct Sent {
    std::uint32_t update_id;
    std::size_t base_size;
    std::size_t actions_size;
  };
  std::vector<Sent> sent_;  // what base_ and sent_actions_ held after each update sent
};

}  // namespace fleet::vda5050
