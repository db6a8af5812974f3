#pragma once

// The order message: a graph of nodes and edges, the released ones being the base the vehicle may
// drive, the rest the horizon it may only plan with (specification 2.1, section 6.6).

#include <nlohmann/json.hpp>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "fleet/core/expected.hpp"
#include "fleet/vda5050/action.hpp"
#include "fleet/vda5050/header.hpp"

namespace fleet::vda5050 {

struct NodePosition {
  double x = 0.0;
  double y = 0.0;
  std::optional<double> theta;
  std::optional<double> allowedDeviationXY;
  std::optional<double> allowedDeviationTheta;
  std::string mapId;
};

struct Node {
  std::string nodeId;
  std::uint32_t sequenceId = 0;  // even: 0, 2, 4, ...
  bool released = false;
  std::optional<NodePosition> nodePosition;
  std::vector<Action> actions;
};

struct Edge {
  std::string edgeId;
  std::uint32_t sequenceId = 0;  // odd: between its start and end node
  bool released = false;
  std::string startNodeId;
  std::string endNodeId;
  std::optional<double> maxSpeed;
  std::optional<double> length;
  std::vector<Action> actions;
};

struct Order {
  Header header;
  std::string orderId;
  std::uint32_t orderUpdateId = 0;
  std::optional<std::string> zoneSetId;
  std::vector<Node> nodes;
  std::vector<Edge> edges;
};

nlohmann::json toJson(const Order& o);
Expected<Order> parseOrder(const nlohmann::json& j);
Expected<Order> parseOrder(const std::string& text);

}  // namespace fleet::vda5050
