// The live dashboard in a real browser: Debian's chromium driven by puppeteer-core
// (tests/browser/dashboard_check.mjs) against a fleet in lockstep (fleet-sim paced at 5x, fleet
// manager, robot agent, WMS adapter with a bearer token). The script checks the login prompt on a
// wrong token, the robots on the page against the simulator's ground truth (which this test writes
// to truth.json from the GroundTruth topic), a task submitted from the page reaching done, pause
// from the page stopping the robot (ground truth again) and the page catching up after an adapter
// restart (asked for through restart.request; this test restarts the adapter on the same port).
// Screenshots go to <build>/reports/dashboard/.

#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>

#include "fleet/transport/dds.hpp"
#include "fleet_stack.hpp"
#include "test_process.hpp"

using namespace fleet;
using namespace std::chrono_literals;
using nlohmann::json;
namespace fs = std::filesystem;

namespace {

using fleet::test::freePort;

/// one_robot.json with three robots at parking places 1, 4 and 7, its site by absolute path.
std::string writeScenario(const fs::path& dir) {
  const std::string src = FLEET_SOURCE_DIR "/sim/scenarios/one_robot.json";
  json s = json::parse(std::ifstream(src));
  s["site"] = (fs::path(FLEET_SOURCE_DIR "/sim/scenarios") / s["site"].get<std::string>()).string();
  s["robots"] = json::array({{{"id", "r1"}, {"start_station", "PARK-1"}},
                             {{"id", "r2"}, {"start_station", "PARK-4"}},
                             {{"id", "r3"}, {"start_station", "PARK-7"}}});
  const auto path = dir / "scenario.json";
  std::ofstream(path) << s.dump(1);
  return path.string();
}

std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

}  // namespace

TEST(DashboardBrowser, LoginRobotsTaskPauseAndRestartInChromium) {
  const fs::path browserDir = FLEET_SOURCE_DIR "/tests/browser";
  if (!fs::exists("/usr/bin/chromium")) {
    GTEST_SKIP() << "chromium not installed (scripts/setup installs it)";
  }
  if (!fs::exists(browserDir / "node_modules/puppeteer-core")) {
    GTEST_SKIP() << "puppeteer-core not installed under tests/browser (scripts/setup installs it)";
  }
  const auto run = test::freshRun("dashboard_");
  const auto& dir = run.dir;
  const std::string scenario = writeScenario(dir);
  const std::string token = "tok-" + run.domain + "-dashboard";
  const int port = freePort();
  ASSERT_GT(port, 0);
  const test::ManagerAndAgent fleet(dir, scenario, run.domain, {"--clock", "lockstep", "--id", "agents"});
  auto adapterEnv = fleet.env;
  adapterEnv.emplace_back("FLEET_WMS_TOKEN", token);
  const std::vector<std::string> adapterArgs = {"--stations",         scenario,      "--port",
                                                std::to_string(port), "--log-level", "warn"};
  auto adapter = std::make_unique<test::ChildProcess>(FLEET_BINARY_DIR "/services/wms_adapter/wms_adapter",
                                                      adapterArgs, adapterEnv);
  test::ChildProcess sim(FLEET_BINARY_DIR "/sim/src/fleet-sim",
                         {"--scenario", scenario, "--clock", "lockstep", "--participants", "1", "--duration",
                          "400", "--max-speed", "5", "--log-level", "warn"},
                         fleet.env);

  // The simulator's ground truth for the script, and adapter restarts when it asks for one.
  std::atomic<bool> stop{false};
  std::atomic<int> restarts{0};
  std::thread helper([&] {
    transport::Participant p;
    transport::Reader<msg::GroundTruth> truth(p);
    while (!stop) {
      truth.waitForData(100ms);
      auto samples = truth.take();
      if (!samples.empty()) {
        const auto& g = samples.back();
        json robots = json::object();
        for (const auto& b : g.bodies) {
          if (b.kind == msg::SourceKind::Robot) {
            robots[b.id] = {b.pose.x, b.pose.y, b.pose.theta, b.v};
          }
        }
        std::ofstream(dir / "truth.json.tmp")
            << json{{"t", static_cast<double>(g.sim_time_ns) / 1e9}, {"robots", robots}}.dump();
        fs::rename(dir / "truth.json.tmp", dir / "truth.json");
      }
      if (fs::exists(dir / "restart.request")) {
        fs::remove(dir / "restart.request");
        adapter->kill(SIGTERM);
        adapter = std::make_unique<test::ChildProcess>(FLEET_BINARY_DIR "/services/wms_adapter/wms_adapter",
                                                       adapterArgs, adapterEnv);
        ++restarts;
        std::ofstream(dir / "restart.done") << "1";
      }
    }
  });

  const fs::path shots = FLEET_BINARY_DIR "/reports/dashboard";
  fs::create_directories(shots);
  const std::string cmd =
      "cd " + browserDir.string() + " && DASH_URL=http://127.0.0.1:" + std::to_string(port) +
      "/dashboard/ DASH_TOKEN=" + token + " DASH_DIR=" + dir.string() + " DASH_SHOTS=" + shots.string() +
      " timeout 240 node dashboard_check.mjs > " + (dir / "browser.log").string() + " 2>&1";
  const int rc = std::system(cmd.c_str());
  stop = true;
  helper.join();
  const std::string log = slurp(dir / "browser.log");
  std::cout << log;
  EXPECT_EQ(rc, 0) << "the browser check failed (screenshots in " << shots << ")";
  EXPECT_EQ(restarts.load(), 1) << "the script never asked for the adapter restart";
  sim.kill(SIGINT);
}
