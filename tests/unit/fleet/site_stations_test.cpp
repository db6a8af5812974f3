// How the fleet manager and the WMS adapter find their stations: a site, a scenario that names one,
// or an older stations file.

#include "fleet/fleet/site_stations.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

namespace fleet {
namespace {

namespace fs = std::filesystem;
const fs::path kScenarios = fs::path(FLEET_SOURCE_DIR) / "sim/scenarios";

TEST(SiteStations, ASiteAndAScenarioNamingItGiveTheSameStations) {
  const auto fromSite = loadStationMap((kScenarios / "small_warehouse.site.json").string());
  const auto fromScenario = loadStationMap((kScenarios / "small_warehouse.json").string());
  ASSERT_TRUE(fromSite) << fromSite.error().message;
  ASSERT_TRUE(fromScenario) << fromScenario.error().message;
  EXPECT_EQ(fromSite->size(), 32u);
  EXPECT_EQ(fromScenario->size(), fromSite->size());
  const Station* p1 = fromScenario->find("P-1");
  ASSERT_NE(p1, nullptr);
  EXPECT_TRUE(p1->has(StationKind::Pickup));
  EXPECT_FALSE(p1->has(StationKind::Dropoff));
  EXPECT_EQ(fromSite->ofKind(StationKind::Parking).size(), 20u);
}

TEST(SiteStations, AnOlderStationsFileStillLoads) {
  const auto dir = fs::temp_directory_path() / "site_stations_old";
  fs::create_directories(dir);
  std::ofstream(dir / "stations.json")
      << R"({"stations": [{"name": "DOCK", "x": 1, "y": 2, "kinds": ["pickup", "dropoff"]}]})";
  const auto m = loadStationMap((dir / "stations.json").string());
  ASSERT_TRUE(m) << m.error().message;
  EXPECT_TRUE(m->find("DOCK")->has(StationKind::Dropoff));
  EXPECT_FALSE(loadSiteFile((dir / "stations.json").string()));  // not a site: no map to plan on
}

TEST(SiteStations, ABadSiteIsRefusedWithItsFileAndKeyPath) {
  const auto dir = fs::temp_directory_path() / "site_stations_bad";
  fs::create_directories(dir);
  auto site = nlohmann::json::parse(std::ifstream(kScenarios / "passage_head_on.site.json"));
  site["stations"][0]["kind"] = "dock";
  std::ofstream(dir / "bad.site.json") << site.dump();
  std::ofstream(dir / "scenario.json") << R"({"site": "bad.site.json", "robots": []})";
  for (const char* f : {"bad.site.json", "scenario.json"}) {
    const auto m = loadStationMap((dir / f).string());
    ASSERT_FALSE(m) << f;
    EXPECT_NE(m.error().message.find("bad.site.json: stations[0].kind: expected one of"), std::string::npos)
        << m.error().message;
  }
  const auto missing = loadStationMap((dir / "nothing.json").string());
  ASSERT_FALSE(missing);
  EXPECT_NE(missing.error().message.find("nothing.json: cannot open the file"), std::string::npos);
}

}  // namespace
}  // namespace fleet
