#include "fleet/avoidance/planner_config.hpp"

#include <limits>
#include <string>

namespace fleet::avoidance {

namespace {
const Range kNonNegative{0.0};
const Range kPositive{0.0, std::numeric_limits<double>::infinity(), true};
}  // namespace

DwaParams dwaParams(Config& cfg, const DwaParams& defaults) {
  DwaParams p = defaults;
  const auto count = [&](const char* key, int fallback) {
    return static_cast<int>(cfg.integer(key, fallback, {1.0, 200.0}));
  };
  p.vSamples = count("v_samples", p.vSamples);
  p.omegaSamples = count("omega_samples", p.omegaSamples);
  p.simTime = cfg.number("sim_time", p.simTime, {0.1, 10.0});
  p.wHeading = cfg.number("w_heading", p.wHeading, kNonNegative);
  p.wClearance = cfg.number("w_clearance", p.wClearance, kNonNegative);
  p.wVelocity = cfg.number("w_velocity", p.wVelocity, kNonNegative);
  p.wProgress = cfg.number("w_progress", p.wProgress, kNonNegative);
  p.wRisk = cfg.number("w_risk", p.wRisk, kNonNegative);
  p.clearanceCap = cfg.number("clearance_cap", p.clearanceCap, kPositive);
  p.clearanceLength = cfg.number("clearance_length", p.clearanceLength, kPositive);
  p.curvatureSpeedFloor = cfg.number("curvature_speed_floor", p.curvatureSpeedFloor, {0.0, 1.0});
  p.minClearance = cfg.number("min_clearance", p.minClearance, kNonNegative);
  p.lookahead = cfg.number("lookahead", p.lookahead, kPositive);
  p.riskSamples = count("risk_samples", p.riskSamples);
  p.discSamples = count("disc_samples", p.discSamples);
  p.allowReverse = cfg.boolean("allow_reverse", p.allowReverse);
  p.stuckCycles = count("stuck_cycles", p.stuckCycles);
  p.stuckProgress = cfg.number("stuck_progress", p.stuckProgress, kNonNegative);
  p.escapeCycles = count("escape_cycles", p.escapeCycles);
  p.prune = cfg.boolean("prune", p.prune);
  cfg.rejectUnknownKeys({"v_samples",
                         "omega_samples",
                         "sim_time",
                         "w_heading",
                         "w_clearance",
                         "w_velocity",
                         "w_progress",
                         "w_risk",
                         "clearance_cap",
                         "clearance_length",
                         "curvature_speed_floor",
                         "min_clearance",
                         "lookahead",
                         "risk_samples",
                         "disc_samples",
                         "allow_reverse",
                         "stuck_cycles",
                         "stuck_progress",
                         "escape_cycles",
                         "prune"});
  if (cfg.ok()) {
    if (auto v = p.validate(); !v)
      cfg.problem("", v.error().message);
  }
  return p;
}

RiskSteppingParams riskSteppingParams(Config& cfg, const RiskSteppingParams& defaults) {
  RiskSteppingParams p = defaults;
  const std::string rule =
      cfg.string("rule", std::string(steppingRuleName(p.rule)), {"iso_level", "weighted"});
  p.rule = rule == "weighted" ? SteppingRule::kWeighted : SteppingRule::kIsoLevel;
  p.levels = static_cast<int>(cfg.integer("levels", p.levels, {1.0, 255.0}));
  p.stepTime = cfg.number("step_time", p.stepTime, kPositive);
  p.candidates = static_cast<int>(cfg.integer("candidates", p.candidates, {1.0, 200.0}));
  p.fan = cfg.number("fan", p.fan, {0.0, 3.14159});
  p.riskSamples = static_cast<int>(cfg.integer("risk_samples", p.riskSamples, {1.0, 100.0}));
  p.wProgress = cfg.number("w_progress", p.wProgress, kNonNegative);
  p.minClearance = cfg.number("min_clearance", p.minClearance, kNonNegative);
  p.kOmega = cfg.number("k_omega", p.kOmega, kPositive);
  p.lookahead = cfg.number("lookahead", p.lookahead, kPositive);
  cfg.rejectUnknownKeys({"rule", "levels", "step_time", "candidates", "fan", "risk_samples", "w_progress",
                         "min_clearance", "k_omega", "lookahead"});
  if (cfg.ok()) {
    if (auto v = p.validate(); !v)
      cfg.problem("", v.error().message);
  }
  return p;
}

SafetyParams safetyParams(Config& cfg) {
  SafetyParams p;
  p.stopMargin = cfg.number("stop_margin", p.stopMargin, kNonNegative);
  p.slowMargin = cfg.number("slow_margin", p.slowMargin, kNonNegative);
  p.slowTime = cfg.number("slow_time", p.slowTime, kNonNegative);
  p.slowRatio = cfg.number("slow_ratio", p.slowRatio, {0.0, 1.0, true});
  p.sampleStep = cfg.number("sample_step", p.sampleStep, {0.001, 1.0});
  p.slowForStatic = cfg.boolean("slow_for_static", p.slowForStatic);
  cfg.rejectUnknownKeys(
      {"stop_margin", "slow_margin", "slow_time", "slow_ratio", "sample_step", "slow_for_static"});
  if (p.slowMargin < p.stopMargin)
    cfg.problem("slow_margin", "must be >= stop_margin (" + std::to_string(p.stopMargin) + ")");
  return p;
}

}  // namespace fleet::avoidance
