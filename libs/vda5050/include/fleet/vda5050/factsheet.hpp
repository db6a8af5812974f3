#pragma once

// The factsheet: what a vehicle is (kinematics, size, speeds) and what of the protocol it supports
// (specification 2.1, section 6.15). The bridge reads the footprint from the 2-D envelopes, or
// from width and length when there are none (footprint()).

#include <nlohmann/json.hpp>

#include <string>
#include <utility>
#include <vector>

#include "fleet/core/expected.hpp"
#include "fleet/vda5050/header.hpp"

namespace fleet::vda5050 {

/// One of agvGeometry.envelopes2d: a polygon in the vehicle's frame (x ahead, y left, m) about its
/// reference point, e.g. its outline unloaded or loaded.
struct Envelope2d {
  std::string set;
  std::vector<std::pair<double, double>> points;  // x, y
};

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
  /// Written as given, or as the width × length rectangle about the centre when empty.
  std::vector<Envelope2d> envelopes2d;
};

/// The disc about the vehicle's reference point that holds it at every heading (it turns on the
/// spot): its radius is the farthest point of any 2-D envelope, or half the diagonal of width ×
/// length when it gives none, and never less than half the larger of width and length. `source`
/// says which, for messages.
struct Footprint {
  double radius = 0.0;
  std::string source;
};
Footprint footprint(const Factsheet& f);

nlohmann::json toJson(const Factsheet& m);
Expected<Factsheet> parseFactsheet(const nlohmann::json& j);
Expected<Factsheet> parseFactsheet(const std::string& text);

}  // namespace fleet::vda5050
