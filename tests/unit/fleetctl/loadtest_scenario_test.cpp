// The load test's scenario stage alone: a file as is, a generated one, and what it refuses.
#include "loadtest_scenario.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

namespace fleet::ctl {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

const std::string kSmall = std::string(FLEET_SOURCE_DIR) + "/sim/scenarios/small_warehouse.json";

fs::path freshDir(const std::string& name) {
  const fs::path d =
      fs::temp_directory_path() / ("loadtest-stage-" + name + "-" + std::to_string(::getpid()));
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

TEST(LoadtestScenario, AFileRunsAsIsWithItsTaskListByTimeAndItsStations) {
  const auto out = freshDir("file");
  LoadtestOptions o;
  o.scenario = kSmall;
  o.durationS = 300;
  auto run = prepareScenario(o, out);
  ASSERT_TRUE(run) << run.error().message;
  EXPECT_EQ(run->robots.size(), 20u);
  EXPECT_TRUE(run->fromList);
  EXPECT_EQ(run->listTasks.size(), 45u);
  for (std::size_t i = 1; i < run->listTasks.size(); ++i) {
    EXPECT_LE(run->listTasks[i - 1].atS, run->listTasks[i].atS);
  }
  EXPECT_FALSE(run->pickups.empty());
  EXPECT_FALSE(run->dropoffs.empty());
  EXPECT_GT(run->widthM, 0.0);
  EXPECT_GT(run->heightM, 0.0);
  // The run's copy: its duration, without fleetctl's own copy of the site's stations.
  std::ifstream in(run->file);
  const json written = json::parse(in);
  EXPECT_EQ(written["duration_s"], 300.0);
  EXPECT_FALSE(written.contains("site_stations"));
  // --generate-tasks keeps the list but does not post it; its rate is 0.75 a robot by default.
  o.generateTasks = true;
  auto generated = prepareScenario(o, out);
  ASSERT_TRUE(generated);
  EXPECT_FALSE(generated->fromList);
  EXPECT_DOUBLE_EQ(taskRatePerMin(o, *generated, 0), 15.0);
  EXPECT_DOUBLE_EQ(taskRatePerMin(o, *run, 45), 9.0);  // the list's 45 over 300 s
}

TEST(LoadtestScenario, AGeneratedScenarioWritesItsSiteIntoTheRunFolder) {
  const auto out = freshDir("generated");
  LoadtestOptions o;
  o.templ = kSmall;
  o.robots = 6;
  o.humans = 2;
  o.durationS = 60;
  auto run = prepareScenario(o, out);
  ASSERT_TRUE(run) << run.error().message;
  EXPECT_EQ(run->robots.size(), 6u);
  EXPECT_FALSE(run->fromList);
  EXPECT_EQ(run->siteFile, fs::absolute(out / "site.json").string());
  EXPECT_TRUE(fs::exists(out / "site.json"));
  EXPECT_TRUE(fs::exists(out / "scenario.json"));
}

TEST(LoadtestScenario, RefusesWhatCannotRunNamingTheFileAndTheFault) {
  const auto out = freshDir("bad");
  LoadtestOptions o;
  o.scenario = (out / "missing.json").string();
  auto missing = prepareScenario(o, out);
  ASSERT_FALSE(missing);
  EXPECT_NE(missing.error().message.find("missing.json: cannot read a JSON scenario"), std::string::npos);

  // A scenario without a site: the traffic manager has no roadmap.
  std::ifstream in(kSmall);
  json s = json::parse(in);
  s.erase("site");
  s.erase("tasks");
  s["stations"] = json::array({{{"name", "P"}, {"kind", "pickup"}, {"x", 1}, {"y", 1}},
                               {{"name", "D"}, {"kind", "dropoff"}, {"x", 2}, {"y", 1}}});
  std::ofstream(out / "nosite.json") << s.dump();
  o.scenario = (out / "nosite.json").string();
  auto noSite = prepareScenario(o, out);
  ASSERT_FALSE(noSite);
  EXPECT_NE(noSite.error().message.find("names no site"), std::string::npos) << noSite.error().message;

  o.scenario = kSmall;
  auto run = prepareScenario(o, out);
  ASSERT_TRUE(run);
  auto stall = checkFaults(*parseFaults({"stall:r99@10+5"}), *run, 1);
  ASSERT_FALSE(stall);
  EXPECT_NE(stall.error().message.find("no robot 'r99'"), std::string::npos);
  auto kill = checkFaults(*parseFaults({"kill-agent@10+2:2"}), *run, 2);
  ASSERT_FALSE(kill);
  EXPECT_NE(kill.error().message.find("only 2 agent process(es)"), std::string::npos);
  EXPECT_TRUE(checkFaults(*parseFaults({"stall:r3@10+5", "kill-agent@10+2:1"}), *run, 2));
}

}  // namespace
}  // namespace fleet::ctl
