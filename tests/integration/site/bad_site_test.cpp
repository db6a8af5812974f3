// Every service refuses a bad site at start: exit code 2, every problem named with the file and the
// key path, and nothing started half-way (no task database created).

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "run_command.hpp"

namespace {

namespace fs = std::filesystem;

using fleet::test::Outcome;

Outcome run(const std::string& cmd) {
  return fleet::test::runCommand(cmd);
}

class BadSite : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("bad_site_" + std::to_string(getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    auto site =
        nlohmann::json::parse(std::ifstream(FLEET_SOURCE_DIR "/sim/scenarios/passage_head_on.site.json"));
    site["stations"][0]["kind"] = "dock";
    site["stations"][1]["pose"] = {0.25, 0.25, 0.0};  // in the wall
    site["colour"] = "blue";
    std::ofstream(dir_ / "bad.site.json") << site.dump(1);
    auto scenario =
        nlohmann::json::parse(std::ifstream(FLEET_SOURCE_DIR "/sim/scenarios/passage_head_on.json"));
    scenario["site"] = "bad.site.json";
    std::ofstream(dir_ / "scenario.json") << scenario.dump(1);
    std::ofstream(dir_ / "risk_map.json") << R"({"site": ")" + (dir_ / "bad.site.json").string() + R"("})";
  }
  void TearDown() override { fs::remove_all(dir_); }

  void expectRefused(const Outcome& r, const std::string& who) {
    EXPECT_EQ(r.code, 2) << who << ":\n" << r.output;
    const std::string file = (dir_ / "bad.site.json").string();
    EXPECT_NE(r.output.find(file + ": colour: unknown key"), std::string::npos) << who << ":\n" << r.output;
    EXPECT_NE(r.output.find(file + ": stations[0].kind: expected one of"), std::string::npos) << who << ":\n"
                                                                                              << r.output;
  }
  fs::path dir_;
};

TEST_F(BadSite, EveryServiceRefusesItWithExitCode2AndEveryProblemNamed) {
  const std::string bin = FLEET_BINARY_DIR;
  const std::string site = (dir_ / "bad.site.json").string();
  expectRefused(run(bin + "/services/fleetctl/fleetctl site check " + site), "fleetctl site check");
  expectRefused(run(bin + "/services/fleet_manager/fleet_manager --stations " + site + " --db " +
                    (dir_ / "fleet.db").string() + " --log-level warn"),
                "fleet_manager");
  EXPECT_FALSE(fs::exists(dir_ / "fleet.db")) << "the manager opened its database before checking the site";
  expectRefused(run(bin + "/services/wms_adapter/wms_adapter --stations " + site + " --port 0"),
                "wms_adapter");
  expectRefused(run(bin + "/services/risk_map/risk_map --config " + (dir_ / "risk_map.json").string()),
                "risk_map");
  expectRefused(run(bin + "/sim/src/fleet-sim --scenario " + (dir_ / "scenario.json").string() +
                    " --clock lockstep --participants 0 --duration 1"),
                "fleet-sim");
}

// The load test hands the risk map the run's site (its "site" key); a path that names no file
// stops it at start with the path in the message, as every other service.
TEST_F(BadSite, TheRiskMapRefusesASiteThatIsNotThereNamingTheFile) {
  const std::string missing = (dir_ / "no-such.site.json").string();
  std::ofstream(dir_ / "risk_map.json") << R"({"site": ")" + missing + R"(", "grid": {"resolution": 0.1}})";
  const auto r = run(std::string(FLEET_BINARY_DIR) + "/services/risk_map/risk_map --config " +
                     (dir_ / "risk_map.json").string());
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find(missing + ": cannot open the file"), std::string::npos) << r.output;
}

TEST_F(BadSite, AStationInTheWallIsReportedOnceTheFileParses) {
  auto site = nlohmann::json::parse(std::ifstream(dir_ / "bad.site.json"));
  site.erase("colour");
  site["stations"][0]["kind"] = "pickup";
  std::ofstream(dir_ / "bad.site.json") << site.dump(1);
  const auto r = run(std::string(FLEET_BINARY_DIR) + "/services/fleetctl/fleetctl site check " +
                     (dir_ / "bad.site.json").string());
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("stations[1].pose: station '"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("is inside an obstacle"), std::string::npos) << r.output;
}

// A site that parses but whose roadmap cannot serve a station: B docks at the end of a dead end one
// robot wide, with no room for a way out apart from its way in (and the site does not say it is
// left by its way in). The traffic manager refuses it at start as `fleetctl site check` does,
// naming the file and the key path; planning round it would send robots in that never come out.
TEST_F(BadSite, AStationWithNoWayOutIsRefusedByTheTrafficManagerNamingTheKeyPath) {
  std::vector<std::string> rows(10, "@" + std::string(20, '.') + "@");
  rows.front() = rows.back() = std::string(22, '@');
  for (const std::size_t y : {1, 2, 3, 6, 7, 8}) {
    for (std::size_t c = 14; c <= 20; ++c) {
      rows[y][c] = '@';
    }
  }
  const nlohmann::json site = {
      {"format", "fleet-site/1"},
      {"name", "dead-end"},
      {"map", {{"rows", rows}, {"resolution", 0.5}}},
      {"robot", {{"radius", 0.3}}},
      {"stations",
       {{{"name", "A"}, {"kind", "pickup"}, {"pose", {1.5, 2.5, 0.0}}},
        {{"name", "B"}, {"kind", "dropoff"}, {"pose", {9.5, 2.5, 3.14159265358979}}}}}};
  const std::string file = (dir_ / "dead-end.site.json").string();
  std::ofstream(file) << site.dump(1);
  const std::string why = "stations[1].exit: station 'B': no room for a way out";
  const auto check = run(std::string(FLEET_BINARY_DIR) + "/services/fleetctl/fleetctl site check " + file);
  EXPECT_EQ(check.code, 2) << check.output;
  EXPECT_NE(check.output.find(why), std::string::npos) << check.output;
  // Bounded: a traffic manager that took the site would plan on until stopped (timeout's code 124).
  const auto tm = run("timeout 20 " + std::string(FLEET_BINARY_DIR) +
                      "/services/traffic_manager/traffic_manager --site " + file);
  EXPECT_EQ(tm.code, 2) << tm.output;
  EXPECT_NE(tm.output.find(file + ": " + why), std::string::npos) << tm.output;
  EXPECT_NE(tm.output.find("refused: 1 roadmap error"), std::string::npos) << tm.output;
}

}  // namespace
