#include "agent_settings.hpp"

#include "fleet/avoidance/local_planner.hpp"
#include "fleet/avoidance/planner_config.hpp"

namespace fleet::agent {

void readSettings(Config& cfg, Settings& s, SetOnCommandLine cli) {
  const std::string local = cfg.string("local_planner", s.localPlanner);
  Config dwa = cfg.child("dwa");
  Config stepping = cfg.child("risk_stepping");
  Config safety = cfg.child("safety");
  s.dwa = avoidance::dwaParams(dwa, s.dwa);
  s.riskStepping = avoidance::riskSteppingParams(stepping, s.riskStepping);
  s.safety = avoidance::safetyParams(safety);
  Config localization = cfg.child("localization");
  s.lineUpdates = localization.boolean("lines", s.lineUpdates);
  localization.rejectUnknownKeys({"lines"});
  Config progress = cfg.child("progress");
  auto& watch = s.progress;
  watch.wantSpeed = progress.number("want_speed", watch.wantSpeed, {0.0, 1.0});
  watch.movedM = progress.number("moved_m", watch.movedM, {0.0, 5.0, true});
  watch.stallS = progress.number("stall_s", watch.stallS, {0.0, 600.0, true});
  watch.recoverS = progress.number("recover_s", watch.recoverS, {0.0, 600.0, true});
  watch.closerM = progress.number("closer_m", watch.closerM, {0.0, 5.0, true});
  watch.failS = progress.number("fail_s", watch.failS, {0.0, 86400.0, true});
  progress.rejectUnknownKeys({"want_speed", "moved_m", "stall_s", "recover_s", "closer_m", "fail_s"});
  cfg.rejectUnknownKeys({"local_planner", "dwa", "risk_stepping", "safety", "localization", "progress"});
  if (!cli.localPlanner) {
    s.localPlanner = local;
  }
  if (s.localPlanner != "follow") {
    if (auto p = avoidance::makePlanner(s.localPlanner); !p) {
      cfg.problem("local_planner", p.error().message + " (or \"follow\")");
    }
  }
}

}  // namespace fleet::agent
