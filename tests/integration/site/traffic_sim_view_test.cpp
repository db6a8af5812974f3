// `fleetctl traffic-sim --html`: the replay page holds the run it shows (every frame, every robot,
// released nodes on the roadmap), and a page it cannot write is bad input (exit 2). Its roadmap
// options reach the roadmap it drives on (--queue-length). Several seeds end with their means.

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "run_command.hpp"

namespace {

namespace fs = std::filesystem;

const std::string kFleetctl = std::string(FLEET_BINARY_DIR) + "/services/fleetctl/fleetctl";
const std::string kSite = std::string(FLEET_SOURCE_DIR) + "/sim/scenarios/small_warehouse.site.json";

TEST(TrafficSimView, ThePageReplaysTheRunItReports) {
  const fs::path page =
      fs::temp_directory_path() / ("traffic_sim_view_" + std::to_string(getpid()) + ".html");
  const auto r =
      fleet::test::runCommand(kFleetctl + " traffic-sim --site " + kSite +
                              " --robots 3 --duration 60 --seeds 1 --json --html " + page.string());
  ASSERT_EQ(r.code, 0) << r.output;
  const auto printed = nlohmann::json::parse(r.output.substr(r.output.find('[')));
  std::ifstream in(page);
  std::stringstream ss;
  ss << in.rdbuf();
  const std::string html = ss.str();
  fs::remove(page);
  const auto at = html.find("const DATA = ");
  ASSERT_NE(at, std::string::npos);
  const auto begin = at + 13;
  const auto end = html.find(";\n", begin);
  const auto data = nlohmann::json::parse(html.substr(begin, end - begin));
  const auto& nodes = data["nodes"];
  const auto& frames = data["frames"];
  ASSERT_GE(frames.size(), 119U);  // one every 0.5 s over 60 s
  ASSERT_LE(frames.size(), 121U);
  double lastT = -1.0;
  std::size_t lastDone = 0;
  bool released = false;
  for (const auto& f : frames) {
    EXPECT_GT(f["t"].get<double>(), lastT);
    lastT = f["t"].get<double>();
    EXPECT_GE(f["done"].get<std::size_t>(), lastDone);
    lastDone = f["done"].get<std::size_t>();
    ASSERT_EQ(f["r"].size(), 3U);
    for (const auto& robot : f["r"]) {
      const double x = robot[0].get<double>();
      const double y = robot[1].get<double>();
      EXPECT_TRUE(x >= 0.0 && x <= 30.0 && y >= 0.0 && y <= 20.0) << robot.dump();
      for (int k : {5, 6}) {
        for (const auto& v : robot[static_cast<std::size_t>(k)]) {
          ASSERT_LT(v.get<std::size_t>(), nodes.size());
        }
      }
      // The base starts where the robot last reported: within one edge of its disc (the longest:
      // a dead-end dock to its exit beside the approach point, √2 m).
      const auto& base = robot[5];
      ASSERT_FALSE(base.empty());
      const auto& b0 = nodes[base[0].get<std::size_t>()];
      EXPECT_LE(std::hypot(b0[0].get<double>() - x, b0[1].get<double>() - y), 1.5) << robot.dump();
      released = released || base.size() > 1;
    }
  }
  EXPECT_TRUE(released);
  // The last frame's count is the run's count (the frame is taken before the last tick's tasks).
  EXPECT_LE(lastDone, printed[0]["tasks_done"].get<std::size_t>());
}

// Several seeds end with their means: the tasks' mean and spread are those of the seeds' own lines,
// and the robot-time ledger and the wait split follow; one seed prints no such line.
TEST(TrafficSimView, SeveralSeedsEndWithTheirMeans) {
  const auto r = fleet::test::runCommand(kFleetctl + " traffic-sim --site " + kSite +
                                         " --robots 6 --duration 120 --seeds 1-3");
  ASSERT_EQ(r.code, 0) << r.output;
  std::vector<double> tasks;
  std::istringstream lines(r.output);
  std::string line, summary;
  while (std::getline(lines, line)) {
    int seed = 0, robots = 0, done = 0;
    double duration = 0.0;
    if (std::sscanf(line.c_str(), "seed %d: %d robots, %lf s: %d tasks", &seed, &robots, &duration, &done) ==
        4)
      tasks.push_back(done);
    if (line.rfind("over ", 0) == 0)
      summary = line;
  }
  ASSERT_EQ(tasks.size(), 3U) << r.output;
  ASSERT_FALSE(summary.empty()) << r.output;
  double mean = 0.0, var = 0.0;
  for (const double t : tasks)
    mean += t / 3.0;
  for (const double t : tasks)
    var += (t - mean) * (t - mean) / 3.0;
  double printedMean = 0.0, printedSd = 0.0;
  ASSERT_EQ(std::sscanf(summary.c_str(), "over 3 seeds: %lf ± %lf tasks", &printedMean, &printedSd), 2)
      << summary;
  EXPECT_NEAR(printedMean, mean, 0.051) << summary;
  EXPECT_NEAR(printedSd, std::sqrt(var), 0.051) << summary;
  EXPECT_NE(summary.find("% of the fleet bound"), std::string::npos) << summary;
  const auto after = r.output.substr(r.output.find(summary));
  EXPECT_NE(after.find("  robot time: no_task"), std::string::npos) << after;
  EXPECT_NE(after.find("  waiting on robots, on what:"), std::string::npos) << after;

  const auto one = fleet::test::runCommand(kFleetctl + " traffic-sim --site " + kSite +
                                           " --robots 6 --duration 120 --seeds 1");
  ASSERT_EQ(one.code, 0) << one.output;
  EXPECT_EQ(one.output.find("\nover "), std::string::npos) << one.output;
}

TEST(TrafficSimView, APageItCannotWriteIsBadInput) {
  const auto r = fleet::test::runCommand(kFleetctl + " traffic-sim --site " + kSite +
                                         " --robots 2 --duration 5 --html /nonexistent-dir/x.html");
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("/nonexistent-dir/x.html"), std::string::npos) << r.output;
}

}  // namespace

// The roadmap of the page: `--queue-length N` generates N queue nodes per station the site gives
// none, so the roadmap grows with N (the small warehouse with its stations' lines taken out: the
// shipped site spells them out); out of range is bad input.
TEST(TrafficSimView, QueueLengthShapesTheRoadmapAndOutOfRangeIsBadInput) {
  auto site = nlohmann::json::parse(std::ifstream(kSite));
  for (auto& st : site["stations"]) {
    st.erase("approach");
    st.erase("queue");
    st.erase("exit");
  }
  const fs::path bare =
      fs::temp_directory_path() / ("traffic_sim_bare_" + std::to_string(getpid()) + ".site.json");
  std::ofstream(bare) << site.dump();
  auto nodesWith = [&bare](const std::string& args) -> long {
    const fs::path page =
        fs::temp_directory_path() / ("traffic_sim_queue_" + std::to_string(getpid()) + ".html");
    const auto r = fleet::test::runCommand(kFleetctl + " traffic-sim --site " + bare.string() +
                                           " --robots 2 --duration 2 " + args + " --html " + page.string());
    EXPECT_EQ(r.code, 0) << r.output;
    std::ifstream in(page);
    std::stringstream ss;
    ss << in.rdbuf();
    fs::remove(page);
    const std::string html = ss.str();
    const auto at = html.find("const DATA = ");
    if (at == std::string::npos) {
      return -1;
    }
    const auto end = html.find(";\n", at + 13);
    return static_cast<long>(nlohmann::json::parse(html.substr(at + 13, end - at - 13))["nodes"].size());
  };
  const long none = nodesWith("--queue-length 0");
  const long one = nodesWith("--queue-length 1 --station-lines 0");
  const long byDefault = nodesWith("");
  EXPECT_GT(none, 0);
  EXPECT_GT(one, none);
  EXPECT_GT(byDefault, one);
  fs::remove(bare);
  const auto r = fleet::test::runCommand(kFleetctl + " traffic-sim --site " + kSite + " --queue-length 51");
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("--queue-length"), std::string::npos) << r.output;
}

// `--core sipp` runs the traffic layer on the timed core (its JSON says so and counts its yields);
// a core it does not know is bad input naming the option.
TEST(TrafficSimView, TheTimedCoreRunsByNameAndAnUnknownCoreIsBadInput) {
  const auto r = fleet::test::runCommand(kFleetctl + " traffic-sim --site " + kSite +
                                         " --robots 6 --duration 60 --core sipp --json");
  ASSERT_EQ(r.code, 0) << r.output;
  const auto j = nlohmann::json::parse(r.output.substr(r.output.find('[')));
  ASSERT_EQ(j.size(), 1U);
  EXPECT_EQ(j[0]["core"], "sipp");
  EXPECT_EQ(j[0]["refused_moves"], 0);
  EXPECT_EQ(j[0]["contacts"], 0);
  EXPECT_TRUE(j[0]["yields"].is_number());
  EXPECT_TRUE(j[0]["refuges"].is_number());
  const auto bad = fleet::test::runCommand(kFleetctl + " traffic-sim --site " + kSite + " --core lacam");
  EXPECT_EQ(bad.code, 2) << bad.output;
  EXPECT_NE(bad.output.find("--core must be pibt or sipp, not 'lacam'"), std::string::npos) << bad.output;
}
