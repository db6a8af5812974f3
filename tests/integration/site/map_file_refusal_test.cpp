// A map file no service can use stops every service at start with exit code 2 and the file named:
// a ROS map whose resolution makes the site kilometres wide (it used to abort `fleetctl site check`
// with std::bad_alloc and grow the traffic manager past 4 GB), and files that are not regular files
// of a sane size (a FIFO used to hang the fleet manager for good; /dev/zero and a sparse 3 GB image
// were read whole before the decoder complained).

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "run_command.hpp"

namespace {

namespace fs = std::filesystem;

using fleet::test::Outcome;

class MapFileRefusal : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("map_file_refusal_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    std::string pixels;
    for (int i = 0; i < 8 * 6; ++i) {
      pixels += "254 ";
    }
    std::ofstream(dir_ / "map.pgm") << "P2\n8 6\n255\n" << pixels << "\n";
  }
  void TearDown() override { fs::remove_all(dir_); }

  // site.json naming a ROS map; `image` and `resolution` go into its side file.
  std::string siteWith(const std::string& name, const std::string& image,
                       const std::string& resolution) const {
    std::ofstream(dir_ / (name + ".yaml"))
        << "image: " << image << "\nresolution: " << resolution << "\norigin: [0, 0, 0]\n";
    const nlohmann::json site = {{"format", "fleet-site/1"},
                                 {"name", name},
                                 {"map", {{"ros", name + ".yaml"}}},
                                 {"stations", nlohmann::json::array()}};
    const fs::path p = dir_ / (name + ".site.json");
    std::ofstream(p) << site.dump(1);
    return p.string();
  }
  // Every command runs under `timeout`: a service that hangs on the file fails the test, not CI.
  static Outcome run(const std::string& cmd) { return fleet::test::runCommand("timeout 60 " + cmd); }
  static std::string bin(const std::string& rel) {
    return std::string(FLEET_BINARY_DIR) + "/services/" + rel;
  }

  void expectRefused(const Outcome& r, const std::string& what, const std::string& who) const {
    EXPECT_EQ(r.code, 2) << who << ":\n" << r.output;
    EXPECT_NE(r.output.find(what), std::string::npos) << who << ": want '" << what << "' in:\n" << r.output;
  }
  fs::path dir_;
};

TEST_F(MapFileRefusal, AHugeResolutionStopsEveryServiceNamingTheSideFileAndTheKey) {
  const std::string site = siteWith("huge", "map.pgm", "1000000");
  const std::string what = (dir_ / "huge.yaml").string() + ": resolution: 1e+06 m per cell makes the map";
  expectRefused(run(bin("fleetctl/fleetctl site check ") + site), what, "fleetctl site check");
  expectRefused(run(bin("fleet_manager/fleet_manager --stations ") + site + " --db " +
                    (dir_ / "fleet.db").string() + " --log-level warn"),
                what, "fleet_manager");
  expectRefused(run(bin("traffic_manager/traffic_manager --site ") + site + " --log-level warn"), what,
                "traffic_manager");
  std::ofstream(dir_ / "risk_map.json") << nlohmann::json{{"site", site}}.dump();
  expectRefused(run(bin("risk_map/risk_map --config ") + (dir_ / "risk_map.json").string()), what,
                "risk_map");
}

TEST_F(MapFileRefusal, AFifoSiteFileIsRefusedAtOnce) {
  const fs::path fifo = dir_ / "fifo.site.json";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  const std::string what = fifo.string() + ": is a FIFO, expected a regular file";
  expectRefused(run(bin("fleetctl/fleetctl site check ") + fifo.string()), what, "fleetctl site check");
  expectRefused(run(bin("fleet_manager/fleet_manager --stations ") + fifo.string() + " --db " +
                    (dir_ / "fleet.db").string() + " --log-level warn"),
                what, "fleet_manager");
  expectRefused(run(bin("fleet_manager/fleet_manager --config ") + fifo.string()), what,
                "fleet_manager --config");
}

TEST_F(MapFileRefusal, ADeviceOrASparseImageIsRefusedWithoutReadingIt) {
  expectRefused(run(bin("fleetctl/fleetctl site check ") + siteWith("zero", "/dev/zero", "0.05")),
                "/dev/zero: is a character device, expected a regular file", "fleetctl site check /dev/zero");
  std::ofstream(dir_ / "sparse.pgm");
  fs::resize_file(dir_ / "sparse.pgm", std::uintmax_t{3} << 30);
  const std::string site = siteWith("sparse", "sparse.pgm", "0.05");
  const std::string what = (dir_ / "sparse.pgm").string() + ": is 3221225472 bytes, more than the limit";
  expectRefused(run(bin("fleetctl/fleetctl site check ") + site), what, "fleetctl site check sparse");
  expectRefused(run(bin("fleet_manager/fleet_manager --stations ") + site + " --db " +
                    (dir_ / "fleet.db").string() + " --log-level warn"),
                what, "fleet_manager sparse");
}

}  // namespace
