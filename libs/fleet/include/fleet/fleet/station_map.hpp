#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <nlohmann/json_fwd.hpp>
#include <string>
#include <string_view>
#include <vector>

#include "fleet/core/expected.hpp"
#include "fleet/core/pose2.hpp"

namespace fleet {

/// What a station is for; one station may serve several purposes (a dock is often both).
enum class StationKind : std::uint8_t { Pickup = 1, Dropoff = 2, Charging = 4, Parking = 8 };

std::string_view toString(StationKind k);

struct Station {
  std::string name;
  Pose2 pose;
  std::uint8_t kinds = 0;  ///< bit set of StationKind

  [[nodiscard]] bool has(StationKind k) const { return (kinds & static_cast<std::uint8_t>(k)) != 0; }
};

/// Named stations of a site: validates task references and gives the poses costs are computed on.
class StationMap {
 public:
  /// Error "invalid" for a bad name or no kind, "conflict" for a name already present.
  Expected<void> add(Station s);
  [[nodiscard]] const Station* find(std::string_view name) const;
  [[nodiscard]] std::vector<const Station*> ofKind(StationKind k) const;
  /// Every station, by name.
  [[nodiscard]] std::vector<const Station*> all() const;
  [[nodiscard]] std::size_t size() const { return stations_.size(); }
  [[nodiscard]] bool empty() const { return stations_.empty(); }

  /// `{"stations": [{"name": "P-1", "x": 1, "y": 2, "theta": 0, "kinds": ["pickup", "dropoff"]}]}`
  /// or the bare array. Every problem is reported ("stations[3].kinds[0]: unknown kind 'dock'").
  static Expected<StationMap> fromJson(const nlohmann::json& doc);

 private:
  std::map<std::string, Station, std::less<>> stations_;
};

}  // namespace fleet
