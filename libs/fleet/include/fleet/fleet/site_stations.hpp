#pragma once

#include <optional>
#include <string>

#include "fleet/core/expected.hpp"
#include "fleet/fleet/station_map.hpp"
#include "fleet/site/site.hpp"

namespace fleet {

/// The site a service runs on, from a site.json (or a bare .map / ROS .yaml), or from a simulator
/// scenario that names one with "site". Errors (code "invalid") list every problem of the file,
/// one per line, each with the file and key path.
/// `checkGeometry` and `mapResolution` as for site::loadSiteOrMap.
Expected<site::Site> loadSiteFile(const std::string& path, bool checkGeometry = true,
                                  double mapResolution = 1.0);

/// What the fleet manager and the WMS adapter read: the site (when the file is one, or a scenario
/// naming one) and the stations they check tasks against — the site's, or, for older setups,
/// those of a stations file ({"stations": [...]}) or of a scenario that carries them inline.
struct SiteStations {
  std::optional<site::Site> site;
  StationMap stations;
};
Expected<SiteStations> loadSiteStations(const std::string& path);
/// Just the stations of loadSiteStations.
Expected<StationMap> loadStationMap(const std::string& path);

/// A site's stations as the fleet library holds them (one kind each).
StationMap stationMapOf(const site::Site& s);

}  // namespace fleet
