#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "fleet/sim/replay.hpp"
#include "sim_fixtures.hpp"

using namespace fleet;
using namespace fleet::sim;

namespace {
std::string slurp(const std::string& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::string writeRun(const std::string& path) {
  auto j = test::room(40, 20);
  j["robots"] = {{{"id", "a"}, {"start", {2.0, 2.5, 0.0}}}};
  j["humans"] = {{"count", 5}};
  World w(test::parse(j));
  auto out = ReplayWriter::open(path);
  EXPECT_TRUE(out);
  EXPECT_TRUE(out->write(replayHeader(w)));
  for (int k = 0; k < 50; ++k) {
    w.command("a", 0.4, 0.1);
    w.advance();
    EXPECT_TRUE(out->write(replayStep(w)));
  }
  EXPECT_TRUE(out->close());
  return summary(w).dump();
}
}  // namespace

TEST(Replay, GzipRoundTripOneObjectPerStepAndByteIdenticalReruns) {
  const auto dir = std::filesystem::temp_directory_path() / ("sim_replay_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string a = (dir / "a.jsonl.gz").string();
  const std::string b = (dir / "b.jsonl.gz").string();
  const std::string sa = writeRun(a);
  const std::string sb = writeRun(b);
  EXPECT_EQ(sa, sb);
  const std::string bytesA = slurp(a);
  ASSERT_GT(bytesA.size(), 10U);
  EXPECT_EQ(static_cast<unsigned char>(bytesA[0]), 0x1f);  // gzip magic
  EXPECT_EQ(static_cast<unsigned char>(bytesA[1]), 0x8b);
  EXPECT_EQ(bytesA, slurp(b));
  auto lines = readReplayLines(a);
  ASSERT_TRUE(lines);
  ASSERT_EQ(lines->size(), 51U);
  const auto header = nlohmann::json::parse((*lines)[0]);
  EXPECT_EQ(header["type"], "header");
  EXPECT_EQ(header["map"]["rows"].size(), 20U);
  for (std::size_t k = 1; k < lines->size(); ++k) {
    const auto s = nlohmann::json::parse((*lines)[k]);
    EXPECT_EQ(s["step"].get<int>(), static_cast<int>(k));
    EXPECT_EQ(s["robots"].size(), 1U);
    EXPECT_EQ(s["humans"].size(), 5U);
  }
  const auto html = viewerHtml(*lines);
  EXPECT_EQ(html.find("/*REPLAY-DATA*/"), std::string::npos);
  EXPECT_NE(html.find("\"type\":\"header\""), std::string::npos);
  EXPECT_EQ(html.find("http://"), std::string::npos);  // self-contained: nothing fetched
  EXPECT_EQ(html.find("https://"), std::string::npos);
  std::filesystem::remove_all(dir);
}

TEST(Replay, SummaryCountsAndPerRobotFigures) {
  auto j = test::room(40, 20);
  j["robots"] = {{{"id", "a"}, {"start", {2.0, 2.5, 0.0}}}};
  World w(test::parse(j));
  for (int k = 0; k < 30; ++k) {
    w.command("a", 0.5, 0.0);
    w.advance();
  }
  w.command("a", std::nan(""), 0.0);
  const auto s = summary(w);
  EXPECT_EQ(s["steps"], 30);
  EXPECT_EQ(s["commands"]["nan_ignored"], 1);
  EXPECT_NEAR(s["per_robot"]["a"]["distance_m"].get<double>(), w.robots()[0].distance, 1e-3);
  EXPECT_EQ(s["contacts"]["robot_shelf"], 0);
}
