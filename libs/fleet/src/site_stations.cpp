#include "fleet/fleet/site_stations.hpp"

#include <filesystem>
#include <nlohmann/json.hpp>

#include "fleet/core/bounded_file.hpp"
#include "fleet/core/config.hpp"
#include "fleet/site/site_loader.hpp"

namespace fleet {

namespace {

std::string joined(const std::vector<std::string>& problems) {
  std::string out;
  for (const auto& p : problems) {
    out += (out.empty() ? "" : "\n") + p;
  }
  return out;
}

Expected<nlohmann::json> readJson(const std::string& path) {
  auto text = readBoundedFile(path, kConfigFileLimit, "invalid");
  if (!text) {
    return unexpected(text.error());
  }
  auto doc = nlohmann::json::parse(*text, nullptr, false);
  if (doc.is_discarded()) {
    return unexpected("invalid", path + ": not valid JSON");
  }
  return doc;
}

// The site file a document stands for: itself, the one a scenario names, or none (older files).
std::string sitePathOf(const std::string& path, const nlohmann::json& doc) {
  if (doc.is_object() && doc.contains("format")) {
    return path;
  }
  if (doc.is_object() && doc.contains("site") && doc["site"].is_string()) {
    const std::filesystem::path p(doc["site"].get<std::string>());
    return (p.is_relative() ? std::filesystem::path(path).parent_path() / p : p).string();
  }
  return "";
}

}  // namespace

Expected<site::Site> loadSiteFile(const std::string& path, bool checkGeometry, double mapResolution) {
  std::string sitePath = path;
  const auto ext = std::filesystem::path(path).extension().string();
  if (ext != ".map" && ext != ".yaml" && ext != ".yml") {
    auto doc = readJson(path);
    if (!doc) {
      return unexpected(doc.error());
    }
    sitePath = sitePathOf(path, *doc);
    if (sitePath.empty()) {
      return unexpected("invalid",
                        path + ": neither a site (no 'format' key) nor a scenario naming one ('site')");
    }
  }
  try {
    return site::loadSiteOrMap(sitePath, mapResolution, checkGeometry);
  } catch (const ConfigError& e) {
    return unexpected("invalid", joined(e.problems()));
  }
}

StationMap stationMapOf(const site::Site& s) {
  StationMap m;
  for (const auto& st : s.stations) {
    const auto kind = st.kind == site::StationKind::Pickup     ? StationKind::Pickup
                      : st.kind == site::StationKind::Dropoff  ? StationKind::Dropoff
                      : st.kind == site::StationKind::Charging ? StationKind::Charging
                                                               : StationKind::Parking;
    // Names are unique in a loaded site, so add() cannot fail here.
    (void)m.add({st.name, st.pose, static_cast<std::uint8_t>(kind)});
  }
  return m;
}

Expected<SiteStations> loadSiteStations(const std::string& path) {
  auto doc = readJson(path);
  if (!doc) {
    return unexpected(doc.error());
  }
  if (!sitePathOf(path, *doc).empty()) {
    auto s = loadSiteFile(path);
    if (!s) {
      return unexpected(s.error());
    }
    SiteStations out{std::move(*s), {}};
    out.stations = stationMapOf(*out.site);
    return out;
  }
  auto m = StationMap::fromJson(*doc);
  if (!m) {
    return unexpected("invalid", path + ": " + m.error().message);
  }
  return SiteStations{std::nullopt, std::move(*m)};
}

Expected<StationMap> loadStationMap(const std::string& path) {
  auto s = loadSiteStations(path);
  if (!s) {
    return unexpected(s.error());
  }
  return std::move(s->stations);
}

}  // namespace fleet
