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
  p.v_samples = count("v_samples", p.v_samples);
  p.omega_samples = count("omega_samples", p.omega_samples);
  p.sim_time = cfg.number("sim_time", p.sim_time, {0.1, 10.0});
  p.w_heading = cfg.number("w_heading", p.w_heading, kNonNegative);
  p.w_clearance = cfg.number("w_clearance", p.w_clearance, kNonNegative);
  p.w_velocity = cfg.number("w_velocity", p.w_velocity, kNonNegative);
  p.w_progress = cfg.number("w_progress", p.w_progress, kNonNegative);
  p.w_risk = cfg.number("w_risk", p.w_risk, kNonNegative);
  p.clearance_cap = cfg.number("clearance_cap", p.clearance_cap, kPositive);
  p.clearance_length = cfg.number("clearance_length", p.clearance_length, kPositive);
  p.curvature_speed_floor = cfg.number("curvature_speed_floor", p.curvature_speed_floor, {0.0, 1.0});
  p.min_clearance = cfg.number("min_clearance", p.min_clearance, kNonNegative);
  p.lookahead = cfg.number("lookahead", p.lookahead, kPositive);
  p.risk_samples = count("risk_samples", p.risk_samples);
  p.disc_samples = count("disc_samples", p.disc_samples);
  p.allow_reverse = cfg.boolean("allow_reverse", p.allow_reverse);
  p.stuck_cycles = count("stuck_cycles", p.stuck_cycles);
  p.stuck_progress = cfg.number("stuck_progress", p.stuck_progress, kNonNegative);
  p.escape_cycles = count("escape_cycles", p.escape_cycles);
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
  p.step_time = cfg.number("step_time", p.step_time, kPositive);
  p.candidates = static_cast<int>(cfg.integer("candidates", p.candidates, {1.0, 200.0}));
  p.fan = cfg.number("fan", p.fan, {0.0, 3.14159});
  p.risk_samples = static_cast<int>(cfg.integer("risk_samples", p.risk_samples, {1.0, 100.0}));
  p.w_progress = cfg.number("w_progress", p.w_progress, kNonNegative);
  p.min_clearance = cfg.number("min_clearance", p.min_clearance, kNonNegative);
  p.k_omega = cfg.number("k_omega", p.k_omega, kPositive);
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
  p.stop_margin = cfg.number("stop_margin", p.stop_margin, kNonNegative);
  p.slow_margin = cfg.number("slow_margin", p.slow_margin, kNonNegative);
  p.slow_time = cfg.number("slow_time", p.slow_time, kNonNegative);
  p.slow_ratio = cfg.number("slow_ratio", p.slow_ratio, {0.0, 1.0, true});
  p.sample_step = cfg.number("sample_step", p.sample_step, {0.001, 1.0});
  cfg.rejectUnknownKeys({"stop_margin", "slow_margin", "slow_time", "slow_ratio", "sample_step"});
  if (p.slow_margin < p.stop_margin)
    cfg.problem("slow_margin", "must be >= stop_margin (" + std::to_string(p.stop_margin) + ")");
  return p;
}

}  // namespace fleet::avoidance
