#include "agent_settings.hpp"

#include "fleet/avoidance/local_planner.hpp"
#include "fleet/avoidance/planner_config.hpp"

namespace fleet::agent {

void readSettings(Config& cfg, Settings& s, SetOnCommandLine cli) {
  const std::string local = cfg.string("local_planner", s.localPlanner);
  const std::string global = cfg.string("global_planner", s.globalPlanner, {"astar", "wavefront", "ompl"});
  const std::string traffic = cfg.string("traffic", s.traffic, {"reactive", "reserved"});
  Config dwa = cfg.child("dwa");
  Config stepping = cfg.child("risk_stepping");
  Config safety = cfg.child("safety");
  s.dwa = avoidance::dwaParams(dwa, s.dwa);
  s.riskStepping = avoidance::riskSteppingParams(stepping, s.riskStepping);
  s.safety = avoidance::safetyParams(safety);
  Config localization = cfg.child("localization");
  s.lineUpdates = localization.boolean("lines", s.lineUpdates);
  localization.rejectUnknownKeys({"lines"});
  cfg.rejectUnknownKeys(
      {"local_planner", "global_planner", "traffic", "dwa", "risk_stepping", "safety", "localization"});
  if (!cli.localPlanner) {
    s.localPlanner = local;
  }
  if (!cli.globalPlanner) {
    s.globalPlanner = global;
  }
  if (!cli.traffic) {
    s.traffic = traffic;
  }
  if (s.localPlanner != "follow") {
    if (auto p = avoidance::makePlanner(s.localPlanner); !p) {
      cfg.problem("local_planner", p.error().message + " (or \"follow\")");
    }
  }
}

}  // namespace fleet::agent
