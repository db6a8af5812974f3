#pragma once

// The factsheet: what a vehicle is (kinematics, size, speeds) and what of the protocol it supports
// (specification 2.1, section 6.15). The bridge reads the footprint from width and length.

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

#include "fleet/core/expected.hpp"
#include "fleet/vda5050/header.hpp"

namespace fleet::vda5050 {

struct Factsheet {
  Header header;
  std::string seriesName;
  std::string agvKinematic = "DIFF";  // DIFF, OMNI, THREEWHEEL
  std::string agvClass = "CARRIER";   // FORKLIFT, CONVEYOR, TUGGER, CARRIER
  double maxLoadMass = 0.0;
  std::vector<std::string> localizationTypes;
  std::vector<std::string> navigationTypes;
  double speedMin = 0.0;
  double speedMax = 0.0;
  double accelerationMax = 0.0;
  double decelerationMax = 0.0;
  double heightMax = 0.0;
  double width = 0.0;
  double length = 0.0;
  double minOrderInterval = 0.0;
  double minStateInterval = 0.0;
  double defaultStateInterval = 1.0;
  std::vector<std::string> agvActions;  // action types the vehicle runs
};

nlohmann::json toJson(const Factsheet& m);
Expected<Factsheet> parseFactsheet(const nlohmann::json& j);
Expected<Factsheet> parseFactsheet(const std::string& text);

}  // namespace fleet::vda5050
