#pragma once

// The vehicle's state message (specification 2.1, section 6.10): order progress, position,
// operating mode, errors, battery, action states and safety state.

#include <nlohmann/json.hpp>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "fleet/core/expected.hpp"
#include "fleet/vda5050/header.hpp"
#include "fleet/vda5050/order.hpp"

namespace fleet::vda5050 {

struct NodeState {
  std::string nodeId;
  std::uint32_t sequenceId = 0;
  bool released = false;
  std::optional<NodePosition> nodePosition;
};

struct EdgeState {
  std::string edgeId;
  std::uint32_t sequenceId = 0;
  bool released = false;
};

struct AgvPosition {
  double x = 0.0;
  double y = 0.0;
  double theta = 0.0;
  std::string mapId;
  bool positionInitialized = true;
};

struct Velocity {
  double vx = 0.0;
  double vy = 0.0;
  double omega = 0.0;
};

struct ActionState {
  std::string actionId;
  std::optional<std::string> actionType;
  std::string actionStatus = "WAITING";  // WAITING, INITIALIZING, RUNNING, FINISHED, FAILED
  std::optional<std::string> resultDescription;
};

struct BatteryState {
  double batteryCharge = 100.0;  // percent
  bool charging = false;
};

struct VehicleError {
  std::string errorType;
  std::string errorLevel = "WARNING";  // WARNING, FATAL
  std::optional<std::string> errorDescription;
  std::vector<std::pair<std::string, std::string>> errorReferences;
};

struct SafetyState {
  std::string eStop = "NONE";  // AUTOACK, MANUAL, REMOTE, NONE
  bool fieldViolation = false;
};

struct State {
  Header header;
  std::string orderId;
  std::uint32_t orderUpdateId = 0;
  std::string lastNodeId;
  std::uint32_t lastNodeSequenceId = 0;
  bool driving = false;
  std::optional<bool> paused;
  std::optional<bool> newBaseRequest;
  std::optional<double> distanceSinceLastNode;
  std::string operatingMode = "AUTOMATIC";  // AUTOMATIC, SEMIAUTOMATIC, MANUAL, SERVICE, TEACHIN
  std::vector<NodeState> nodeStates;
  std::vector<EdgeState> edgeStates;
  std::optional<AgvPosition> agvPosition;
  std::optional<Velocity> velocity;
  std::vector<ActionState> actionStates;
  BatteryState batteryState;
  std::vector<VehicleError> errors;
  SafetyState safetyState;
};

nlohmann::json toJson(const State& m);
Expected<State> parseState(const nlohmann::json& j);
Expected<State> parseState(const std::string& text);

}  // namespace fleet::vda5050
