#include "fleet/avoidance/planner_config.hpp"

#include <gtest/gtest.h>

#include <string>

namespace fleet::avoidance {
namespace {

bool mentions(const Config& c, const std::string& what) {
  for (const auto& p : c.problems()) {
    if (p.find(what) != std::string::npos)
      return true;
  }
  return false;
}

TEST(PlannerConfig, DwaWeightsAndSamplesComeFromConfig) {
  Config cfg = Config::fromText(
      R"({"dwa": {"w_risk": 2.5, "w_heading": 0.4, "v_samples": 14, "omega_samples": 12, "sim_time": 2.0,
                  "allow_reverse": true}})",
      "agent.json");
  Config d = cfg.child("dwa");
  const DwaParams p = dwaParams(d);
  EXPECT_TRUE(cfg.ok());
  EXPECT_DOUBLE_EQ(p.wRisk, 2.5);
  EXPECT_DOUBLE_EQ(p.wHeading, 0.4);
  EXPECT_EQ(p.vSamples, 14);
  EXPECT_EQ(p.omegaSamples, 12);
  EXPECT_DOUBLE_EQ(p.simTime, 2.0);
  EXPECT_TRUE(p.allowReverse);
  // Untouched keys keep the Nav2-like defaults.
  EXPECT_DOUBLE_EQ(p.wClearance, DwaParams{}.wClearance);
  DynamicWindowPlanner planner(p);
  EXPECT_EQ(planner.params().vSamples, 14);
}

TEST(PlannerConfig, EveryBadDwaKeyIsNamed) {
  Config cfg =
      Config::fromText(R"({"dwa": {"w_risk": -1, "v_samples": "many", "w_speed": 1}})", "agent.json");
  Config d = cfg.child("dwa");
  (void)dwaParams(d);
  EXPECT_EQ(cfg.problems().size(), 3u);
  EXPECT_TRUE(mentions(cfg, "agent.json: dwa.w_risk"));
  EXPECT_TRUE(mentions(cfg, "agent.json: dwa.v_samples"));
  EXPECT_TRUE(mentions(cfg, "agent.json: dwa.w_speed: unknown key"));
  EXPECT_THROW(cfg.finish(), ConfigError);
}

TEST(PlannerConfig, RiskSteppingRuleAndLevelsComeFromConfig) {
  Config cfg = Config::fromText(R"({"risk_stepping": {"rule": "weighted", "levels": 5, "lookahead": 1.5}})",
                                "agent.json");
  Config c = cfg.child("risk_stepping");
  const RiskSteppingParams p = riskSteppingParams(c);
  EXPECT_TRUE(cfg.ok());
  EXPECT_EQ(p.rule, SteppingRule::kWeighted);
  EXPECT_EQ(p.levels, 5);
  EXPECT_DOUBLE_EQ(p.lookahead, 1.5);
  EXPECT_EQ(RiskSteppingParams{}.rule, SteppingRule::kIsoLevel);

  Config bad = Config::fromText(R"({"rule": "greedy", "levels": 0, "fan_out": 1})", "r.json");
  (void)riskSteppingParams(bad);
  EXPECT_EQ(bad.problems().size(), 3u);
  EXPECT_TRUE(mentions(bad, "r.json: rule"));
  EXPECT_TRUE(mentions(bad, "r.json: levels"));
  EXPECT_TRUE(mentions(bad, "r.json: fan_out: unknown key"));
}

TEST(PlannerConfig, SafetyZonesAndTheirOrder) {
  Config ok = Config::fromText(R"({"stop_margin": 0.1, "slow_margin": 0.5, "slow_ratio": 0.4})", "s.json");
  const SafetyParams p = safetyParams(ok);
  EXPECT_TRUE(ok.ok());
  EXPECT_DOUBLE_EQ(p.stopMargin, 0.1);
  EXPECT_DOUBLE_EQ(p.slowMargin, 0.5);
  EXPECT_DOUBLE_EQ(p.slowRatio, 0.4);
  EXPECT_TRUE(p.slowForStatic);
  EXPECT_TRUE(p.validate().has_value());
  Config off = Config::fromText(R"({"slow_for_static": false})", "s.json");
  EXPECT_FALSE(safetyParams(off).slowForStatic);
  EXPECT_TRUE(off.ok());

  Config bad = Config::fromText(R"({"stop_margin": 0.4, "slow_margin": 0.2, "slow_ratio": 0})", "s.json");
  (void)safetyParams(bad);
  EXPECT_TRUE(mentions(bad, "s.json: slow_margin: must be >= stop_margin"));
  EXPECT_TRUE(mentions(bad, "s.json: slow_ratio"));
}

}  // namespace
}  // namespace fleet::avoidance
