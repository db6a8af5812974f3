// DDS Security end to end: identities made by scripts/dds-security, Cyclone DDS's
// security plugins, and participants that should or should not get a Task to the fleet manager.

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <string>

#include <nlohmann/json.hpp>
#include <sstream>

#include "test_process.hpp"

using namespace fleet;
using namespace std::chrono_literals;

namespace {

const std::string kProbe = FLEET_BINARY_DIR "/tests/integration/security/dds_probe";
const std::string kScript = FLEET_SOURCE_DIR "/scripts/dds-security";
const std::string kSim = FLEET_BINARY_DIR "/sim/src/fleet-sim";
const std::string kCircle = FLEET_SOURCE_DIR "/sim/scenarios/circle_swap.json";

int sh(const std::string& cmd) {
  return std::system((cmd + " >/dev/null 2>&1").c_str());
}

std::map<std::string, int> counts(const std::filesystem::path& file) {
  std::map<std::string, int> out;
  std::ifstream in(file);
  std::string prefix;
  int n = 0;
  while (in >> prefix >> n) {
    out[prefix] = n;
  }
  return out;
}

/// How many samples of `key` a probe counted (0: none).
int of(const std::map<std::string, int>& counted, const std::string& key) {
  const auto it = counted.find(key);
  return it == counted.end() ? 0 : it->second;
}

class DdsSecurity : public ::testing::Test {
 protected:
  void SetUp() override {
    domain_ = std::to_string(test::uniqueDomain());
    dir_ = std::filesystem::temp_directory_path() / ("fleet_dds_security_" + domain_);
    std::filesystem::remove_all(dir_);
    // "agents" may speak for robot r1 only.
    ASSERT_EQ(sh(kScript + " deployment " + (dir_ / "site").string() + " agents=r1"), 0);
    // The same names under another site's CA: valid certificates, but not this site's.
    ASSERT_EQ(sh(kScript + " init " + (dir_ / "other").string()), 0);
    ASSERT_EQ(sh(kScript + " identity " + (dir_ / "other").string() + " wms-adapter wms-adapter"), 0);
  }
  void TearDown() override {
    if (!HasFailure()) {
      std::filesystem::remove_all(dir_);
    }
  }
  /// Environment of a process running as `identity` of `site` ("" : no security at all).
  std::vector<std::pair<std::string, std::string>> as(const std::string& site,
                                                      const std::string& identity) const {
    std::vector<std::pair<std::string, std::string>> env = {{"FLEET_DDS_DOMAIN", domain_}};
    env.emplace_back("CYCLONEDDS_URI",
                     site.empty() ? "" : "file://" + (dir_ / site / identity / "cyclonedds.xml").string());
    return env;
  }
  /// The simulator (wall clock, circle_swap: robots r1..r8, no people) driven for a while by an
  /// agent's commands for r1 and by commands for r3 written in r1's partition, and, where `theirs`
  /// is set, for r2 in r2's partition; returns the simulator's summary.
  nlohmann::json commandRun(const std::string& site, int* theirsExit) {
    const auto summary = dir_ / (site.empty() ? "plain_summary.json" : "summary.json");
    test::ChildProcess sim(kSim,
                           {"--scenario", kCircle, "--clock", "wall", "--duration", "14", "--summary",
                            summary.string(), "--log-level", "warn"},
                           as(site, "simulator"));
    std::this_thread::sleep_for(1s);
    test::ChildProcess own(kProbe, {"command", "10", "r1", "r1"}, as(site, "agents"));
    test::ChildProcess disguised(kProbe, {"command", "10", "r3", "r1"}, as(site, "agents"));
    std::optional<test::ChildProcess> theirs;
    if (theirsExit != nullptr) {
      theirs.emplace(kProbe, std::vector<std::string>{"command", "10", "r2", "r2"}, as(site, "agents"));
    }
    EXPECT_EQ(own.wait(40s), 0);
    EXPECT_EQ(disguised.wait(40s), 0) << "its own partition is granted";
    if (theirs) {
      *theirsExit = theirs->wait(40s);
    }
    EXPECT_EQ(sim.wait(40s), 0);
    std::ifstream in(summary);
    std::stringstream ss;
    ss << in.rdbuf();
    return nlohmann::json::parse(ss.str(), nullptr, false);
  }
  /// The Tasks, by prefix, that a probe with the fleet manager's certificate reads while `writers`
  /// (which starts the writing probes and waits for them) runs.
  std::map<std::string, int> managerReadsWhile(const std::function<void()>& writers) {
    const auto got = dir_ / "manager.txt";
    test::ChildProcess manager(kProbe, {"read", "16", got.string()}, as("site", "fleet-manager"));
    std::this_thread::sleep_for(1s);
    writers();
    EXPECT_EQ(manager.wait(40s), 0);
    return counts(got);
  }
  std::string domain_;
  std::filesystem::path dir_;
};

}  // namespace

TEST_F(DdsSecurity, OnlyTheAdaptersCertificateGetsATaskToTheManager) {
  const auto plainGot = dir_ / "plain.txt";
  test::ChildProcess plainReader(kProbe, {"read", "16", plainGot.string()}, as("", ""));
  const auto m = managerReadsWhile([&] {
    test::ChildProcess adapter(kProbe, {"write", "12", "adapter"}, as("site", "wms-adapter"));
    test::ChildProcess plain(kProbe, {"write", "12", "plain"}, as("", ""));
    test::ChildProcess robot(kProbe, {"write", "12", "robot"}, as("site", "agents"));
    test::ChildProcess foreign(kProbe, {"write", "12", "foreign"}, as("other", "wms-adapter"));
    EXPECT_EQ(adapter.wait(40s), 0);
    EXPECT_EQ(plain.wait(40s), 0) << "an unsecured participant runs, alone";
    EXPECT_EQ(robot.wait(40s), 3) << "a robot's permissions do not include writing Task";
    EXPECT_EQ(foreign.wait(40s), 0) << "another site's certificate is valid for itself";
  });
  ASSERT_EQ(plainReader.wait(40s), 0);
  EXPECT_GT(of(m, "adapter"), 50) << "the secured adapter's tasks arrive";
  EXPECT_EQ(of(m, "plain"), 0) << "no certificate: not admitted";
  EXPECT_EQ(of(m, "foreign"), 0) << "another site's CA: not authenticated";
  EXPECT_EQ(of(m, "robot"), 0);
  const auto p = counts(plainGot);
  EXPECT_EQ(of(p, "adapter"), 0) << "an unsecured reader sees nothing of the secured fleet";
  EXPECT_GT(of(p, "plain"), 50) << "(the unsecured pair talks among itself: the probe works)";
}

TEST_F(DdsSecurity, AReadOnlyObserverCannotWrite) {
  test::ChildProcess observer(kProbe, {"write", "2", "observer"}, as("site", "observer"));
  EXPECT_EQ(observer.wait(40s), 3);
  const auto got = dir_ / "observer.txt";
  test::ChildProcess reader(kProbe, {"read", "2", got.string()}, as("site", "observer"));
  EXPECT_EQ(reader.wait(40s), 0) << "but it may read Task";
}

TEST_F(DdsSecurity, AnAgentSpeaksOnlyForItsOwnRobots) {
  // The fleet manager's view of RobotState and TaskStatus, through the same readers it uses.
  const auto got = dir_ / "manager_states.txt";
  test::ChildProcess manager(kProbe, {"states", "16", got.string()}, as("site", "fleet-manager"));
  std::this_thread::sleep_for(1s);
  test::ChildProcess own(kProbe, {"speak", "12", "r1", "r1"}, as("site", "agents"));
  test::ChildProcess theirs(kProbe, {"speak", "12", "r2", "r2"}, as("site", "agents"));
  test::ChildProcess disguised(kProbe, {"speak", "12", "r3", "r1"}, as("site", "agents"));
  EXPECT_EQ(own.wait(40s), 0);
  EXPECT_EQ(theirs.wait(40s), 3) << "r2's partition is not in the agents' permissions: writer refused";
  EXPECT_EQ(disguised.wait(40s), 0) << "its own partition is granted";
  ASSERT_EQ(manager.wait(40s), 0);
  const auto m = counts(got);
  EXPECT_GT(of(m, "state:r1"), 20) << "the agent's own robot is heard";
  EXPECT_GT(of(m, "status:r1"), 20);
  EXPECT_EQ(of(m, "state:r2") + of(m, "status:r2"), 0);
  EXPECT_EQ(of(m, "state:r3") + of(m, "status:r3"), 0) << "r3's samples in r1's partition are dropped";
  EXPECT_GT(of(m, "foreign"), 20) << "and counted";
}

TEST_F(DdsSecurity, WithoutSecurityTheReceiverStillDropsARobotSpeakingForAnother) {
  // Loopback development: partitions are the same, nothing refuses the writer, the readers' check
  // still holds.
  const auto got = dir_ / "plain_states.txt";
  test::ChildProcess manager(kProbe, {"states", "10", got.string()}, as("", ""));
  std::this_thread::sleep_for(1s);
  test::ChildProcess own(kProbe, {"speak", "6", "r1", "r1"}, as("", ""));
  test::ChildProcess disguised(kProbe, {"speak", "6", "r3", "r1"}, as("", ""));
  EXPECT_EQ(own.wait(40s), 0);
  EXPECT_EQ(disguised.wait(40s), 0);
  ASSERT_EQ(manager.wait(40s), 0);
  const auto m = counts(got);
  EXPECT_GT(of(m, "state:r1"), 10);
  EXPECT_EQ(of(m, "state:r3") + of(m, "status:r3"), 0);
  EXPECT_GT(of(m, "foreign"), 10);
}

TEST_F(DdsSecurity, AnAgentCommandsOnlyItsOwnRobots) {
  int theirs = -1;
  const auto s = commandRun("site", &theirs);
  EXPECT_EQ(theirs, 3) << "r2's partition is not in the agents' permissions: command writer refused";
  ASSERT_TRUE(s.is_object()) << "the simulator wrote its summary";
  EXPECT_GT(s["per_robot"]["r1"]["distance_m"].get<double>(), 0.5) << "the agent drives its own robot";
  EXPECT_EQ(s["per_robot"]["r2"]["distance_m"].get<double>(), 0.0);
  EXPECT_EQ(s["per_robot"]["r3"]["distance_m"].get<double>(), 0.0)
      << "r3's commands in r1's partition are dropped";
  EXPECT_GT(s["commands"]["foreign_robot"].get<int>(), 20) << "and counted";
}

TEST_F(DdsSecurity, WithoutSecurityTheSimulatorStillDropsACommandForAnotherRobot) {
  const auto s = commandRun("", nullptr);
  ASSERT_TRUE(s.is_object()) << "the simulator wrote its summary";
  EXPECT_GT(s["per_robot"]["r1"]["distance_m"].get<double>(), 0.5);
  EXPECT_EQ(s["per_robot"]["r3"]["distance_m"].get<double>(), 0.0);
  EXPECT_GT(s["commands"]["foreign_robot"].get<int>(), 20);
}

TEST_F(DdsSecurity, ARevokedIdentityIsRefused) {
  const auto site = dir_ / "site";
  ASSERT_EQ(sh(kScript + " identity " + site.string() + " old-adapter wms-adapter"), 0);
  ASSERT_EQ(sh(kScript + " revoke " + site.string() + " old-adapter"), 0);
  // Whoever holds the revoked key is not bound to the site's config: the same without the list.
  {
    std::ifstream in(site / "old-adapter" / "cyclonedds.xml");
    std::ofstream out(site / "old-adapter" / "nocrl.xml");
    for (std::string line; std::getline(in, line);) {
      if (line.find("<CRL>") == std::string::npos) {
        out << line << "\n";
      }
    }
  }
  auto stolenEnv = as("site", "old-adapter");
  stolenEnv.back().second = "file://" + (site / "old-adapter" / "nocrl.xml").string();
  const auto m = managerReadsWhile([&] {
    test::ChildProcess adapter(kProbe, {"write", "12", "adapter"}, as("site", "wms-adapter"));
    test::ChildProcess revoked(kProbe, {"write", "12", "revoked"}, as("site", "old-adapter"));
    test::ChildProcess stolen(kProbe, {"write", "12", "stolen"}, stolenEnv);
    EXPECT_EQ(revoked.wait(40s), 4) << "its own config names the list: its participant is refused";
    EXPECT_EQ(stolen.wait(40s), 0) << "without the list it starts, alone";
    EXPECT_EQ(adapter.wait(40s), 0);
  });
  EXPECT_GT(of(m, "adapter"), 50) << "the valid adapter's tasks arrive";
  EXPECT_EQ(of(m, "stolen") + of(m, "revoked"), 0) << "the revoked certificate is not authenticated";
}
