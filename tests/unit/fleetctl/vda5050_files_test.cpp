// `fleetctl vda5050-files` and `loadtest --vda5050`: the broker's, bridge's and simulator's files
// for a set of vehicles, as a container deployment reads them (paths of the mount, not of the
// directory they were written to) and with credentials that agree across the three.

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "vda5050_setup.hpp"

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

std::string slurp(const fs::path& p) {
  std::ifstream f(p);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

class Vda5050Files : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!fs::exists("/usr/bin/mosquitto_passwd")) {
      GTEST_SKIP() << "mosquitto is not installed (scripts/setup installs it)";
    }
    dir_ = fs::temp_directory_path() / ("vda5050-files-" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

TEST_F(Vda5050Files, ForAContainerThePathsAreTheMountsAndTheCredentialsAgree) {
  fleet::ctl::Vda5050Files f;
  f.out = dir_;
  f.seen_at = "/etc/fleet/vda5050";
  f.log_to_file = false;
  f.robots = {"r2", "r3"};
  f.map_id = "small-warehouse";
  f.broker_host = "mosquitto";
  f.bind_address = "0.0.0.0";
  f.port = 18831;
  ASSERT_TRUE(fleet::ctl::writeVda5050Files(f));

  const std::string conf = slurp(dir_ / "mosquitto.conf");
  EXPECT_NE(conf.find("listener 18831 0.0.0.0\n"), std::string::npos) << conf;
  EXPECT_NE(conf.find("allow_anonymous false\n"), std::string::npos) << conf;
  EXPECT_NE(conf.find("password_file /etc/fleet/vda5050/mosquitto.passwd\n"), std::string::npos) << conf;
  EXPECT_NE(conf.find("acl_file /etc/fleet/vda5050/mosquitto.acl\n"), std::string::npos) << conf;
  EXPECT_NE(conf.find("log_dest stderr\n"), std::string::npos) << conf;
  EXPECT_EQ(conf.find(dir_.string()), std::string::npos) << "a host path leaked into the broker's config";
  EXPECT_EQ(conf.find("\nuser "), std::string::npos) << "in a container the broker runs as the image's user";

  const std::string acl = slurp(dir_ / "mosquitto.acl");
  EXPECT_NE(acl.find("user fleet-sim-r2\ntopic readwrite uagv/v2/fleet-sim/r2/#\n"), std::string::npos)
      << acl;
  EXPECT_NE(acl.find("user fleet-sim-r3\ntopic readwrite uagv/v2/fleet-sim/r3/#\n"), std::string::npos)
      << acl;

  const auto bridge = json::parse(slurp(dir_ / "vda5050_bridge.json"));
  const auto vehicles = json::parse(slurp(dir_ / "vda5050_vehicles.json"));
  EXPECT_EQ(bridge["broker"]["host"], "mosquitto");
  EXPECT_EQ(bridge["broker"]["port"], 18831);
  EXPECT_EQ(bridge["broker"]["username"], "master");
  EXPECT_EQ(bridge["map_id"], "small-warehouse");
  EXPECT_EQ(bridge["lockstep"], true);
  ASSERT_EQ(bridge["vehicles"].size(), 2U);
  EXPECT_EQ(bridge["vehicles"][1]["robot"], "r3");
  EXPECT_EQ(vehicles["broker"]["host"], "mosquitto");
  ASSERT_EQ(vehicles["vehicles"].size(), 2U);

  // Hashed, one line per user, no password in clear; readable by its owner only.
  const std::string passwd = slurp(dir_ / "mosquitto.passwd");
  EXPECT_EQ(std::count(passwd.begin(), passwd.end(), '\n'), 3) << passwd;
  for (const auto& v : vehicles["vehicles"]) {
    const std::string pw = v["password"];
    EXPECT_GE(pw.size(), 16U);
    EXPECT_EQ(passwd.find(pw), std::string::npos) << "a password in clear";
  }
  EXPECT_EQ(passwd.find(bridge["broker"]["password"].get<std::string>()), std::string::npos);
  EXPECT_NE(vehicles["vehicles"][0]["password"], vehicles["vehicles"][1]["password"]);
  EXPECT_EQ(
      fs::status(dir_ / "mosquitto.passwd").permissions() & (fs::perms::group_all | fs::perms::others_all),
      fs::perms::none);
}

TEST_F(Vda5050Files, OnThisMachineTheBrokerLogsBesideItsFilesOnLoopback) {
  fleet::ctl::Vda5050Files f;
  f.out = dir_;
  f.robots = {"r1"};
  f.map_id = "m";
  f.port = 18832;
  f.sim_clock = false;
  ASSERT_TRUE(fleet::ctl::writeVda5050Files(f));
  const std::string conf = slurp(dir_ / "mosquitto.conf");
  EXPECT_NE(conf.find("listener 18832 127.0.0.1\n"), std::string::npos) << conf;
  // A vehicle (or anyone with its credentials) cannot make the broker carry huge messages.
  EXPECT_NE(conf.find("message_size_limit 262144\n"), std::string::npos) << conf;
  EXPECT_NE(conf.find("log_dest file " + (dir_ / "mosquitto.log").string()), std::string::npos) << conf;
  const auto bridge = json::parse(slurp(dir_ / "vda5050_bridge.json"));
  EXPECT_FALSE(bridge["broker"].contains("host"));  // the bridge's default, 127.0.0.1
  EXPECT_EQ(bridge["clock"], "wall");
  EXPECT_EQ(bridge["lockstep"], false);
}

TEST_F(Vda5050Files, AnUnwritableDirectoryIsAnErrorNamingIt) {
  fleet::ctl::Vda5050Files f;
  f.out = dir_ / "missing" / "deeper";
  f.robots = {"r1"};
  f.map_id = "m";
  f.port = 18833;
  const auto r = fleet::ctl::writeVda5050Files(f);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find((dir_ / "missing" / "deeper").string()), std::string::npos)
      << r.error().message;
}

}  // namespace
