#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "fleet/risk/rle.hpp"
#include "risk_map_node.hpp"

using namespace fleet;
using ::testing::HasSubstr;

namespace {
riskmap::Settings small() {
  auto cfg =
      Config::fromText(R"({"grid": {"width": 100, "height": 100, "resolution": 0.1}, "steps": 10})", "t");
  auto s = riskmap::readSettings(cfg);
  cfg.finish();
  return s;
}

msg::PredictedDiscs source(const std::string& id, float x, float y, std::int64_t t0) {
  msg::PredictedDiscs m{id, msg::SourceKind::Robot, t0, 0.1f, {}};
  for (int k = 0; k < 10; ++k) {
    m.discs.push_back({x + 0.05f * static_cast<float>(k), y, 0.4f, 0.05f});
  }
  return m;
}
}  // namespace

TEST(RiskMapNode, SettingsErrorsNameTheKey) {
  auto cfg = Config::fromText(R"({"levels": 0, "model": "magic", "lockstep": true, "gird": {}})", "rm.json");
  (void)riskmap::readSettings(cfg);
  std::string msg;
  try {
    cfg.finish();
  } catch (const ConfigError& e) {
    msg = e.what();
  }
  EXPECT_THAT(msg, HasSubstr("rm.json: levels: expected an integer in [1, 255], got 0"));
  EXPECT_THAT(msg, HasSubstr("rm.json: model: expected one of \"gaussian\", \"overlap\", got \"magic\""));
  EXPECT_THAT(msg, HasSubstr("rm.json: lockstep: requires \"clock\": \"sim\""));
  EXPECT_THAT(msg, HasSubstr("rm.json: gird: unknown key"));
}

TEST(RiskMapNode, AGridOverASiteCoversEveryCellOfIt) {
  auto cfg = Config::fromText(R"({"site": "s.json", "grid": {"resolution": 0.1, "width": 300}})", "rm.json");
  const auto s = riskmap::readSettings(cfg);
  EXPECT_EQ(s.site, "s.json");
  ASSERT_FALSE(cfg.ok());
  EXPECT_THAT(cfg.problems()[0], HasSubstr("rm.json: grid.width: comes from the site"));
  // 30 m / 0.1 m is 299.99999999999994 in doubles: still 300 cells, and 0.25 m cells cover 30 m
  // with 120; a map 30.05 m wide needs 301 cells of 0.1 m.
  const auto g = riskmap::gridOverSite({-1.0, 2.0}, 30.0, 20.0, 0.1);
  EXPECT_EQ(g.width, 300);
  EXPECT_EQ(g.height, 200);
  EXPECT_DOUBLE_EQ(g.originX, -1.0);
  EXPECT_EQ(riskmap::gridOverSite({}, 30.0, 20.0, 0.25).width, 120);
  EXPECT_EQ(riskmap::gridOverSite({}, 30.05, 20.0, 0.1).width, 301);
}

TEST(RiskMapNode, BadSamplesAreRefusedAndStateKept) {
  auto node = riskmap::RiskMapNode::create(small());
  ASSERT_TRUE(node);
  const std::int64_t now = 1'000'000'000'000;
  ASSERT_TRUE(node->accept(source("a", 4, 5, now), now));
  ASSERT_TRUE(node->accept(source("b", 4.5f, 5, now), now));
  const auto before = node->fuse(now);
  ASSERT_EQ(before.sources, 2u);

  auto nan = source("a", 4, 5, now);
  nan.discs[3].x = std::numeric_limits<float>::quiet_NaN();
  auto neg = source("a", 4, 5, now);
  neg.discs[0].r = -1;
  auto dt = source("a", 4, 5, now);
  dt.dt = 0;
  auto future = source("a", 4, 5, now + 3600LL * 1'000'000'000);
  auto many = source("a", 4, 5, now);
  many.discs.resize(500, many.discs[0]);
  for (const auto& bad : {nan, neg, dt, future, many}) {
    EXPECT_FALSE(node->accept(bad, now));
  }
  EXPECT_EQ(node->rejected(), 5u);
  const auto after = node->fuse(now);
  EXPECT_EQ(after.runs, before.runs) << "refused samples must not change the map";
}

TEST(RiskMapNode, StaleSourcesAreDropped) {
  auto node = riskmap::RiskMapNode::create(small());
  ASSERT_TRUE(node);
  const std::int64_t t = 5'000'000'000;
  ASSERT_TRUE(node->accept(source("a", 4, 5, t), t));
  ASSERT_TRUE(node->accept(source("b", 4.5f, 5, t), t));
  EXPECT_EQ(node->fuse(t + 500'000'000).sources, 2u);
  EXPECT_EQ(node->fuse(t + 1'500'000'000).sources, 0u);
  EXPECT_EQ(node->dropped_stale(), 2u);
}

TEST(RiskMapNode, MessageDecodesToTheEngineLevels) {
  auto node = riskmap::RiskMapNode::create(small());
  ASSERT_TRUE(node);
  const std::int64_t t = 5'000'000'000;
  ASSERT_TRUE(node->accept(source("a", 4, 5, t), t));
  ASSERT_TRUE(node->accept(source("b", 4.6f, 5.1f, t), t));
  const auto m = node->fuse(t);
  std::vector<risk::LevelRun> runs;
  for (const auto& r : m.runs) {
    runs.push_back({r.level, r.count});
  }
  auto levels = risk::decodeRle(runs, m.width * m.height, m.levels);
  ASSERT_TRUE(levels);
  EXPECT_EQ(*levels, node->engine().result().levels.level);
  EXPECT_GT(m.scene_index, 0.0f);
  EXPECT_FALSE(m.regions.empty());
  int maxLevel = 0;
  for (auto l : *levels) {
    maxLevel = std::max<int>(maxLevel, l);
  }
  EXPECT_GT(maxLevel, 0);
}
