#include "fleet/vda5050/order.hpp"

#include "json_reader.hpp"

namespace fleet::vda5050 {

namespace {

nlohmann::json actionsJson(const std::vector<Action>& actions) {
  auto j = nlohmann::json::array();
  for (const auto& a : actions) {
    j.push_back(toJson(a));
  }
  return j;
}

std::vector<Action> readActions(const detail::JsonReader& r) {
  std::vector<Action> out;
  for (const auto& a : r.array("actions")) {
    out.push_back(detail::readAction(a));
  }
  return out;
}

}  // namespace

namespace detail {

nlohmann::json nodePositionJson(const NodePosition& p) {
  nlohmann::json j{{"x", p.x}, {"y", p.y}, {"mapId", p.mapId}};
  if (p.theta) {
    j["theta"] = *p.theta;
  }
  if (p.allowedDeviationXY) {
    j["allowedDeviationXY"] = *p.allowedDeviationXY;
  }
  if (p.allowedDeviationTheta) {
    j["allowedDeviationTheta"] = *p.allowedDeviationTheta;
  }
  return j;
}

NodePosition readNodePosition(const JsonReader& r) {
  NodePosition p;
  p.x = r.number("x");
  p.y = r.number("y");
  p.theta = r.optNumber("theta");
  p.allowedDeviationXY = r.optNumber("allowedDeviationXY");
  p.allowedDeviationTheta = r.optNumber("allowedDeviationTheta");
  p.mapId = r.str("mapId");
  return p;
}

}  // namespace detail

nlohmann::json toJson(const Order& o) {
  nlohmann::json j;
  writeHeader(j, o.header);
  j["orderId"] = o.orderId;
  j["orderUpdateId"] = o.orderUpdateId;
  if (o.zoneSetId) {
    j["zoneSetId"] = *o.zoneSetId;
  }
  auto& nodes = j["nodes"] = nlohmann::json::array();
  for (const auto& n : o.nodes) {
    nlohmann::json jn{{"nodeId", n.nodeId}, {"sequenceId", n.sequenceId}, {"released", n.released}};
    if (n.nodePosition) {
      jn["nodePosition"] = detail::nodePositionJson(*n.nodePosition);
    }
    jn["actions"] = actionsJson(n.actions);
    nodes.push_back(std::move(jn));
  }
  auto& edges = j["edges"] = nlohmann::json::array();
  for (const auto& e : o.edges) {
    nlohmann::json je{{"edgeId", e.edgeId},
                      {"sequenceId", e.sequenceId},
                      {"released", e.released},
                      {"startNodeId", e.startNodeId},
                      {"endNodeId", e.endNodeId}};
    if (e.maxSpeed) {
      je["maxSpeed"] = *e.maxSpeed;
    }
    if (e.length) {
      je["length"] = *e.length;
    }
    je["actions"] = actionsJson(e.actions);
    edges.push_back(std::move(je));
  }
  return j;
}

Expected<Order> parseOrder(const nlohmann::json& j) {
  return detail::parseAs<Order>(j, "order", [](const detail::JsonReader& r) {
    Order o;
    o.header = detail::readHeader(r);
    o.orderId = r.str("orderId");
    o.orderUpdateId = static_cast<std::uint32_t>(r.uint("orderUpdateId"));
    o.zoneSetId = r.optStr("zoneSetId");
    for (const auto& n : r.array("nodes")) {
      Node node;
      node.nodeId = n.str("nodeId");
      node.sequenceId = static_cast<std::uint32_t>(n.uint("sequenceId"));
      node.released = n.boolean("released");
      if (n.has("nodePosition")) {
        node.nodePosition = detail::readNodePosition(n.object("nodePosition"));
      }
      node.actions = readActions(n);
      o.nodes.push_back(std::move(node));
    }
    for (const auto& e : r.array("edges")) {
      Edge edge;
      edge.edgeId = e.str("edgeId");
      edge.sequenceId = static_cast<std::uint32_t>(e.uint("sequenceId"));
      edge.released = e.boolean("released");
      edge.startNodeId = e.str("startNodeId");
      edge.endNodeId = e.str("endNodeId");
      edge.maxSpeed = e.optNumber("maxSpeed");
      edge.length = e.optNumber("length");
      edge.actions = readActions(e);
      o.edges.push_back(std::move(edge));
    }
    return o;
  });
}

Expected<Order> parseOrder(const std::string& text) {
  return detail::parseTextWith<Order>(text, "order", &parseOrder);
}

}  // namespace fleet::vda5050
