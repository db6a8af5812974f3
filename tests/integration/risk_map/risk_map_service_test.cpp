// The running risk_map service (a separate process) fuses what a source process publishes; its
// RiskMap must equal the library's own fusion of the same discs at the same time, cell for cell.

#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <thread>

#include "fleet/core/clock.hpp"
#include "fleet/risk/rle.hpp"
#include "fleet/transport/dds.hpp"
#include "risk_map_node.hpp"
#include "test_process.hpp"

using namespace fleet;
using namespace std::chrono_literals;

TEST(RiskMapService, PublishedMapMatchesLibraryFusion) {
  const std::string domain = std::to_string(test::uniqueDomain());
  setenv("FLEET_DDS_DOMAIN", domain.c_str(), 1);
  const auto cfgPath = std::filesystem::temp_directory_path() / ("risk_map_" + domain + ".json");
  const std::string cfgText =
      R"({"grid": {"width": 200, "height": 200, "resolution": 0.1}, "steps": 20, "rate_hz": 20, "stale_after_s": 30})";
  std::ofstream(cfgPath) << cfgText;
  test::ChildProcess service(FLEET_BINARY_DIR "/services/risk_map/risk_map", {"--config", cfgPath.string()},
                             {{"FLEET_DDS_DOMAIN", domain}});

  transport::Participant p;
  transport::Writer<msg::PredictedDiscs> out(p);
  out.forRobots({"src-0", "src-1", ""});  // two robots' partitions and the default one (the human)
  transport::Reader<msg::RiskMap> in(p);
  const auto deadline = std::chrono::steady_clock::now() + 20s;
  while ((out.matchedReaders() == 0 || in.matchedWriters() == 0) &&
         std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(10ms);
  }
  ASSERT_GT(out.matchedReaders(), 0u);

  // Two robots converging and a human crossing, predicted 2 s ahead.
  WallClock wall;
  const std::int64_t t0 = wall.nowNs();
  std::vector<msg::PredictedDiscs> sources;
  for (int s = 0; s < 3; ++s) {
    msg::PredictedDiscs m{
        "src-" + std::to_string(s), s == 2 ? msg::SourceKind::Human : msg::SourceKind::Robot, t0, 0.1f, {}};
    for (int k = 0; k < 20; ++k) {
      const float f = static_cast<float>(k) * 0.1f;
      const float x = s == 0 ? 8.0f + f : (s == 1 ? 12.0f - f : 10.0f);
      const float y = s == 2 ? 6.0f + 2.0f * f : 10.0f;
      m.discs.push_back({x, y, 0.4f, 0.05f + 0.02f * f});
    }
    sources.push_back(m);
  }
  // Best-effort topic: repeat until the service reports all three sources.
  std::optional<msg::RiskMap> got;
  while (!got && std::chrono::steady_clock::now() < deadline) {
    for (const auto& m : sources) {
      out.write(m);
    }
    in.waitForData(100ms);
    for (auto& m : in.take()) {
      if (m.sources == 3) {
        got = m;
      }
    }
  }
  ASSERT_TRUE(got) << "no RiskMap with the three sources arrived";

  auto cfg = Config::fromText(cfgText, "test");
  auto node = riskmap::RiskMapNode::create(riskmap::readSettings(cfg));
  ASSERT_TRUE(node);
  for (const auto& m : sources) {
    ASSERT_TRUE(node->accept(m, got->stamp_ns));
  }
  const auto expected = node->fuse(got->stamp_ns);
  EXPECT_EQ(got->width, expected.width);
  EXPECT_EQ(got->levels, expected.levels);
  EXPECT_FLOAT_EQ(got->scene_index, expected.scene_index);
  EXPECT_EQ(got->runs, expected.runs);
  EXPECT_EQ(got->regions.size(), expected.regions.size());
  EXPECT_GT(got->runs.size(), 3u) << "the map should not be empty";
  std::filesystem::remove(cfgPath);
}
