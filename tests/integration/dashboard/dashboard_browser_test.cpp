// The live dashboard in a real browser: Debian's chromium driven by puppeteer-core
// (tests/browser/dashboard_check.mjs) against a fleet in lockstep (fleet-sim paced at 5x, fleet
// manager, robot agent, a traffic manager, WMS adapter with a token file: a read-only and an
// operator token). The script checks the login prompt on a wrong token, that a read-only session
// is offered no action, the robots on the page against the simulator's ground truth (which this
// test writes to truth.json from the GroundTruth topic), the traffic manager's roadmap and station
// queues on the map and a release in its robot's colour (this test publishes one over DDS for r9, a
// robot no agent drives, so the traffic manager never replaces it and nothing follows it), the
// layer switches, a task submitted from the page reaching done, pause from the page stopping the
// robot (ground truth again) and the page catching up after an adapter restart (asked for through
// restart.request; this test restarts the adapter on the same port), the people the robots see
// drawn where the simulator has its one person, and the contacts and near-miss figures.
// Screenshots go to <build>/reports/dashboard/.

#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <optional>
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

/// The robot of the test's own release: none of the scenario's (r1 to r3, which the traffic manager
/// releases to), so its route stays as published and no robot drives it.
const std::string kReleasedTo = "r9";

using fleet::test::freePort;

/// one_robot.json with three robots at parking places 1, 4 and 7, its site by absolute path, and a
/// person pacing slowly by the west wall, in sight of r1 and out of every robot's way (the robots
/// publish the people they see; the page draws those).
std::string writeScenario(const fs::path& dir) {
  const std::string src = FLEET_SOURCE_DIR "/sim/scenarios/one_robot.json";
  json s = json::parse(std::ifstream(src));
  s["site"] = (fs::path(FLEET_SOURCE_DIR "/sim/scenarios") / s["site"].get<std::string>()).string();
  s["robots"] = json::array({{{"id", "r1"}, {"start_station", "PARK-1"}},
                             {{"id", "r2"}, {"start_station", "PARK-4"}},
                             {{"id", "r3"}, {"start_station", "PARK-7"}}});
  s["humans"] = {
      {"count", 0},
      {"list", json::array({{{"id", "h1"},
                             {"start", {2.0, 2.6}},
                             {"route", json::array({json::array({2.0, 3.2}), json::array({2.0, 2.6})})},
                             {"speed", 0.3}}})}};
  const auto path = dir / "scenario.json";
  std::ofstream(path) << s.dump(1);
  return path.string();
}

/// A release for `robot` in the roadmap's epoch: a walk of nine nodes from the node nearest
/// (x, y), always to the unvisited neighbour farthest from the start (a straight-ish line), the
/// first five released, the rest planned.
msg::TrafficRelease releaseNear(const msg::Roadmap& m, const std::string& robot, double x, double y) {
  std::int32_t at = 0;
  for (std::size_t i = 0; i < m.nodes.size(); ++i) {
    const auto& n = m.nodes[i];
    const auto& best = m.nodes[static_cast<std::size_t>(at)];
    if (std::hypot(n.x - x, n.y - y) < std::hypot(best.x - x, best.y - y)) {
      at = static_cast<std::int32_t>(i);
    }
  }
  const auto start = m.nodes[static_cast<std::size_t>(at)];
  std::vector<std::int32_t> walk = {at};
  while (walk.size() < 9) {
    std::int32_t next = -1;
    double far = -1;
    for (const auto& e : m.edges) {
      const auto& n = m.nodes[static_cast<std::size_t>(e.to)];
      const double d = std::hypot(n.x - start.x, n.y - start.y);
      if (e.from == walk.back() && e.open && std::find(walk.begin(), walk.end(), e.to) == walk.end() &&
          d > far) {
        next = e.to;
        far = d;
      }
    }
    if (next < 0) {
      break;
    }
    walk.push_back(next);
  }
  msg::TrafficRelease r;
  r.robot_id = robot;
  r.epoch = m.epoch;
  r.seq = 1;
  for (std::size_t i = 0; i < walk.size(); ++i) {
    (i < 5 ? r.base : r.horizon).push_back(m.nodes[static_cast<std::size_t>(walk[i])]);
  }
  return r;
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
  const std::string token = "tok-" + run.domain + "-dashboard-operator";
  const std::string viewerToken = "tok-" + run.domain + "-dashboard-viewer";
  const int port = freePort();
  ASSERT_GT(port, 0);
  const test::ManagerAndAgent fleet(dir, scenario, run.domain, {"--clock", "lockstep", "--id", "agents"});
  std::ofstream(dir / "tokens") << "floor read,submit,operate " << token << "\nviewer read " << viewerToken
                                << "\n";
  std::ofstream(dir / "adapter.json") << json{{"http", {{"token_file", (dir / "tokens").string()}}}}.dump();
  const auto adapterEnv = fleet.env;
  const std::vector<std::string> adapterArgs = {"--config",    (dir / "adapter.json").string(),
                                                "--stations",  scenario,
                                                "--port",      std::to_string(port),
                                                "--log-level", "warn"};
  auto adapter = std::make_unique<test::ChildProcess>(FLEET_BINARY_DIR "/services/wms_adapter/wms_adapter",
                                                      adapterArgs, adapterEnv);
  test::ChildProcess sim(FLEET_BINARY_DIR "/sim/src/fleet-sim",
                         {"--scenario", scenario, "--clock", "lockstep", "--participants",
                          test::ManagerAndAgent::kLockstepParticipants, "--duration", "400", "--max-speed",
                          "5", "--log-level", "warn"},
                         fleet.env);

  // The simulator's ground truth for the script, and adapter restarts when it asks for one.
  std::atomic<bool> stop{false};
  std::atomic<int> restarts{0};
  std::atomic<bool> released{false};
  std::thread helper([&] {
    transport::Participant p;
    transport::Reader<msg::GroundTruth> truth(p);
    transport::Reader<msg::Roadmap> roadmaps(p);
    transport::Writer<msg::TrafficRelease> releases(p);  // transient-local: a restarted adapter gets it too
    std::optional<msg::Roadmap> roadmap;
    while (!stop) {
      truth.waitForData(100ms);
      if (auto m = roadmaps.take(); !m.empty()) {
        roadmap = m.back();
      }
      auto samples = truth.take();
      if (!samples.empty()) {
        const auto& g = samples.back();
        for (const auto& b : g.bodies) {
          if (roadmap && !released && b.id == "r3") {  // drawn from where r3 stands
            releases.write(releaseNear(*roadmap, kReleasedTo, b.pose.x, b.pose.y));
            released = true;
          }
        }
        json robots = json::object();
        json humans = json::object();
        for (const auto& b : g.bodies) {
          if (b.kind == msg::SourceKind::Robot) {
            robots[b.id] = {b.pose.x, b.pose.y, b.pose.theta, b.v};
          } else {
            humans[b.id] = {b.pose.x, b.pose.y};
          }
        }
        std::ofstream(dir / "truth.json.tmp") << json{
            {"t", static_cast<double>(g.sim_time_ns) / 1e9},
            {"robots", robots},
            {"humans", humans}}.dump();
        fs::rename(dir / "truth.json.tmp", dir / "truth.json");
      }
      if (fs::exists(dir / "restart.request")) {
        fs::remove(dir / "restart.request");
        // As a service manager restarts it: the new one once the old one has let go of the port
        // (started at once, it sometimes bound before the old one had closed it, and exited).
        adapter->kill(SIGTERM);
        (void)adapter->wait(10s);
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
      " DASH_VIEWER_TOKEN=" + viewerToken + " DASH_RELEASED=" + kReleasedTo +
      " timeout 240 node dashboard_check.mjs > " + (dir / "browser.log").string() + " 2>&1";
  const int rc = std::system(cmd.c_str());
  stop = true;
  helper.join();
  const std::string log = slurp(dir / "browser.log");
  std::cout << log;
  EXPECT_EQ(rc, 0) << "the browser check failed (screenshots in " << shots << ")";
  EXPECT_EQ(restarts.load(), 1) << "the script never asked for the adapter restart";
  EXPECT_TRUE(released) << "no roadmap from the traffic manager to release a route on";
  sim.kill(SIGINT);
}
