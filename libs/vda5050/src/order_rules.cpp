#include "fleet/vda5050/order_rules.hpp"

namespace fleet::vda5050 {

namespace {
std::string at(const char* kind, std::size_t i) {
  return std::string("order.") + kind + "[" + std::to_string(i) + "]";
}
}  // namespace

Expected<void> validateOrder(const Order& order) {
  const auto bad = [](std::string msg) { return unexpected("vda5050.validation", std::move(msg)); };
  if (order.orderId.empty()) {
    return bad("order.orderId: empty");
  }
  if (order.nodes.empty()) {
    return bad("order.nodes: an order needs at least one node");
  }
  if (order.edges.size() + 1 != order.nodes.size()) {
    return bad("order.edges: " + std::to_string(order.edges.size()) + " edges for " +
               std::to_string(order.nodes.size()) + " nodes (expected one fewer)");
  }
  if (!order.nodes.front().released) {
    return bad("order.nodes[0].released: the first node must be released");
  }
  if (order.nodes.front().sequenceId % 2 != 0) {
    return bad("order.nodes[0].sequenceId: node sequenceIds are even");
  }
  bool in_horizon = false;
  const std::string& map = order.nodes.front().nodePosition ? order.nodes.front().nodePosition->mapId : "";
  for (std::size_t i = 0; i < order.nodes.size(); ++i) {
    const auto& n = order.nodes[i];
    if (n.nodeId.empty()) {
      return bad(at("nodes", i) + ".nodeId: empty");
    }
    const auto expected = order.nodes.front().sequenceId + static_cast<std::uint32_t>(2 * i);
    if (n.sequenceId != expected) {
      return bad(at("nodes", i) + ".sequenceId: expected " + std::to_string(expected) + ", got " +
                 std::to_string(n.sequenceId));
    }
    if (n.released && in_horizon) {
      return bad(at("nodes", i) + ".released: a released node after the horizon began");
    }
    in_horizon = in_horizon || !n.released;
    if (n.nodePosition && n.nodePosition->mapId != map) {
      return bad(at("nodes", i) + ".nodePosition.mapId: '" + n.nodePosition->mapId + "' differs from '" +
                 map + "'");
    }
  }
  for (std::size_t i = 0; i < order.edges.size(); ++i) {
    const auto& e = order.edges[i];
    const auto& from = order.nodes[i];
    const auto& to = order.nodes[i + 1];
    if (e.sequenceId != from.sequenceId + 1) {
      return bad(at("edges", i) + ".sequenceId: expected " + std::to_string(from.sequenceId + 1) + ", got " +
                 std::to_string(e.sequenceId));
    }
    if (e.startNodeId != from.nodeId || e.endNodeId != to.nodeId) {
      return bad(at("edges", i) + ": joins '" + e.startNodeId + "' to '" + e.endNodeId + "', expected '" +
                 from.nodeId + "' to '" + to.nodeId + "'");
    }
    if (e.released != to.released) {
      return bad(at("edges", i) +
                 ".released: must equal its end node's (an edge is base exactly when its end node is)");
    }
  }
  return {};
}

std::optional<Node> baseEnd(const Order& order) {
  std::optional<Node> last;
  for (const auto& n : order.nodes) {
    if (!n.released) {
      break;
    }
    last = n;
  }
  return last;
}

OrderVerdict judgeOrder(const OrderProgress& progress, const Order& order) {
  if (auto ok = validateOrder(order); !ok) {
    return {OrderDecision::kReject, "validationError", ok.error().message};
  }
  const auto& first = order.nodes.front();
  if (order.orderId != progress.orderId) {
    if (progress.active) {
      return {OrderDecision::kReject, "orderError",
              "new orderId '" + order.orderId + "' while order '" + progress.orderId +
                  "' is still running (finish or cancel it first)"};
    }
    if (!progress.lastNodeId.empty() && first.nodeId != progress.lastNodeId) {
      return {OrderDecision::kReject, "noRouteError",
              "order '" + order.orderId + "' starts at '" + first.nodeId + "', the vehicle stands at '" +
                  progress.lastNodeId + "'"};
    }
    return {OrderDecision::kAcceptNew, {}, {}};
  }
  if (order.orderUpdateId == progress.orderUpdateId) {
    return {OrderDecision::kDiscardDuplicate, {}, {}};
  }
  if (order.orderUpdateId < progress.orderUpdateId) {
    return {OrderDecision::kReject, "orderUpdateError",
            "orderUpdateId " + std::to_string(order.orderUpdateId) + " is older than the current " +
                std::to_string(progress.orderUpdateId)};
  }
  if (first.nodeId != progress.baseEndNodeId || first.sequenceId != progress.baseEndSequenceId) {
    return {OrderDecision::kReject, "orderUpdateError",
            "update " + std::to_string(order.orderUpdateId) + " starts at '" + first.nodeId +
                "' (sequenceId " + std::to_string(first.sequenceId) + "), not at the base end '" +
                progress.baseEndNodeId + "' (sequenceId " + std::to_string(progress.baseEndSequenceId) +
                "): it does not extend the base"};
  }
  return {OrderDecision::kAcceptUpdate, {}, {}};
}

Order stitchOrder(const Order& current, const Order& update) {
  Order out = update;
  out.nodes.clear();
  out.edges.clear();
  const auto& stitch = update.nodes.front();
  for (const auto& n : current.nodes) {
    if (!n.released || n.sequenceId > stitch.sequenceId) {
      break;
    }
    out.nodes.push_back(n);
  }
  for (const auto& e : current.edges) {
    if (!e.released || e.sequenceId > stitch.sequenceId) {
      break;
    }
    out.edges.push_back(e);
  }
  if (!out.nodes.empty() && out.nodes.back().sequenceId == stitch.sequenceId) {
    auto& actions = out.nodes.back().actions;
    actions.insert(actions.end(), stitch.actions.begin(), stitch.actions.end());
  } else {
    out.nodes.push_back(stitch);
  }
  out.nodes.insert(out.nodes.end(), update.nodes.begin() + 1, update.nodes.end());
  out.edges.insert(out.edges.end(), update.edges.begin(), update.edges.end());
  return out;
}

}  // namespace fleet::vda5050
