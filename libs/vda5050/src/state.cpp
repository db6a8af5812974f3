#include "fleet/vda5050/state.hpp"

#include "json_reader.hpp"

namespace fleet::vda5050 {

nlohmann::json toJson(const State& m) {
  nlohmann::json j;
  writeHeader(j, m.header);
  j["orderId"] = m.orderId;
  j["orderUpdateId"] = m.orderUpdateId;
  j["lastNodeId"] = m.lastNodeId;
  j["lastNodeSequenceId"] = m.lastNodeSequenceId;
  j["driving"] = m.driving;
  if (m.paused) {
    j["paused"] = *m.paused;
  }
  if (m.newBaseRequest) {
    j["newBaseRequest"] = *m.newBaseRequest;
  }
  if (m.distanceSinceLastNode) {
    j["distanceSinceLastNode"] = *m.distanceSinceLastNode;
  }
  j["operatingMode"] = m.operatingMode;
  auto& nodes = j["nodeStates"] = nlohmann::json::array();
  for (const auto& n : m.nodeStates) {
    nlohmann::json jn{{"nodeId", n.nodeId}, {"sequenceId", n.sequenceId}, {"released", n.released}};
    if (n.nodePosition) {
      // The state's nodePosition has only x, y, theta and mapId.
      nlohmann::json p{{"x", n.nodePosition->x}, {"y", n.nodePosition->y}, {"mapId", n.nodePosition->mapId}};
      if (n.nodePosition->theta) {
        p["theta"] = *n.nodePosition->theta;
      }
      jn["nodePosition"] = std::move(p);
    }
    nodes.push_back(std::move(jn));
  }
  auto& edges = j["edgeStates"] = nlohmann::json::array();
  for (const auto& e : m.edgeStates) {
    edges.push_back({{"edgeId", e.edgeId}, {"sequenceId", e.sequenceId}, {"released", e.released}});
  }
  if (m.agvPosition) {
    j["agvPosition"] = {{"x", m.agvPosition->x},
                        {"y", m.agvPosition->y},
                        {"theta", m.agvPosition->theta},
                        {"mapId", m.agvPosition->mapId},
                        {"positionInitialized", m.agvPosition->positionInitialized}};
  }
  if (m.velocity) {
    j["velocity"] = {{"vx", m.velocity->vx}, {"vy", m.velocity->vy}, {"omega", m.velocity->omega}};
  }
  auto& actions = j["actionStates"] = nlohmann::json::array();
  for (const auto& a : m.actionStates) {
    nlohmann::json ja{{"actionId", a.actionId}, {"actionStatus", a.actionStatus}};
    if (a.actionType) {
      ja["actionType"] = *a.actionType;
    }
    if (a.resultDescription) {
      ja["resultDescription"] = *a.resultDescription;
    }
    actions.push_back(std::move(ja));
  }
  j["batteryState"] = {{"batteryCharge", m.batteryState.batteryCharge},
                       {"charging", m.batteryState.charging}};
  auto& errors = j["errors"] = nlohmann::json::array();
  for (const auto& e : m.errors) {
    nlohmann::json je{{"errorType", e.errorType}, {"errorLevel", e.errorLevel}};
    if (e.errorDescription) {
      je["errorDescription"] = *e.errorDescription;
    }
    if (!e.errorReferences.empty()) {
      auto& refs = je["errorReferences"] = nlohmann::json::array();
      for (const auto& [k, v] : e.errorReferences) {
        refs.push_back({{"referenceKey", k}, {"referenceValue", v}});
      }
    }
    errors.push_back(std::move(je));
  }
  j["information"] = nlohmann::json::array();
  j["safetyState"] = {{"eStop", m.safetyState.eStop}, {"fieldViolation", m.safetyState.fieldViolation}};
  return j;
}

Expected<State> parseState(const nlohmann::json& j) {
  return detail::parseAs<State>(j, "state", [](const detail::JsonReader& r) {
    State m;
    m.header = detail::readHeader(r);
    m.orderId = r.str("orderId");
    m.orderUpdateId = static_cast<std::uint32_t>(r.uint("orderUpdateId"));
    m.lastNodeId = r.str("lastNodeId");
    m.lastNodeSequenceId = static_cast<std::uint32_t>(r.uint("lastNodeSequenceId"));
    m.driving = r.boolean("driving");
    m.paused = r.optBoolean("paused");
    m.newBaseRequest = r.optBoolean("newBaseRequest");
    m.distanceSinceLastNode = r.optNumber("distanceSinceLastNode");
    m.operatingMode =
        r.oneOf("operatingMode", {"AUTOMATIC", "SEMIAUTOMATIC", "MANUAL", "SERVICE", "TEACHIN"});
    for (const auto& n : r.array("nodeStates")) {
      NodeState s{
          n.str("nodeId"), static_cast<std::uint32_t>(n.uint("sequenceId")), n.boolean("released"), {}};
      if (n.has("nodePosition")) {
        const auto p = n.object("nodePosition");
        s.nodePosition =
            NodePosition{p.number("x"), p.number("y"), p.optNumber("theta"), {}, {}, p.str("mapId")};
      }
      m.nodeStates.push_back(std::move(s));
    }
    for (const auto& e : r.array("edgeStates")) {
      m.edgeStates.push_back(
          {e.str("edgeId"), static_cast<std::uint32_t>(e.uint("sequenceId")), e.boolean("released")});
    }
    if (r.has("agvPosition")) {
      const auto p = r.object("agvPosition");
      m.agvPosition = AgvPosition{p.number("x"), p.number("y"), p.number("theta"), p.str("mapId"),
                                  p.boolean("positionInitialized")};
    }
    if (r.has("velocity")) {
      const auto v = r.object("velocity");
      m.velocity = Velocity{v.optNumber("vx").value_or(0.0), v.optNumber("vy").value_or(0.0),
                            v.optNumber("omega").value_or(0.0)};
    }
    for (const auto& a : r.array("actionStates")) {
      m.actionStates.push_back(
          {a.str("actionId"), a.optStr("actionType"),
           a.oneOf("actionStatus", {"WAITING", "INITIALIZING", "RUNNING", "FINISHED", "FAILED"}),
           a.optStr("resultDescription")});
    }
    const auto b = r.object("batteryState");
    m.batteryState = {b.number("batteryCharge"), b.boolean("charging")};
    for (const auto& e : r.array("errors")) {
      VehicleError err{
          e.str("errorType"), e.oneOf("errorLevel", {"WARNING", "FATAL"}), e.optStr("errorDescription"), {}};
      for (const auto& ref : e.optArray("errorReferences")) {
        err.errorReferences.emplace_back(ref.str("referenceKey"), ref.str("referenceValue"));
      }
      m.errors.push_back(std::move(err));
    }
    const auto s = r.object("safetyState");
    m.safetyState = {s.oneOf("eStop", {"AUTOACK", "MANUAL", "REMOTE", "NONE"}), s.boolean("fieldViolation")};
    return m;
  });
}

Expected<State> parseState(const std::string& text) {
  return detail::parseTextWith<State>(text, "state", &parseState);
}

}  // namespace fleet::vda5050
