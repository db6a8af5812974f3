#include "task_goals.hpp"

#include "fleet/core/clock.hpp"
#include "fleet/fleet/errors.hpp"

namespace fleet::manager {
namespace {

msg::GoalAction actionOf(StepAction a) {
  switch (a) {
    case StepAction::Pick:
      return msg::GoalAction::Load;
    case StepAction::Drop:
      return msg::GoalAction::Unload;
    case StepAction::Charge:
      return msg::GoalAction::Charge;
    case StepAction::Goto:
    case StepAction::Wait:
      break;
  }
  return msg::GoalAction::None;
}

}  // namespace

Expected<std::vector<msg::Goal>> taskGoals(const Task& t, const StationMap& stations, double chargeMaxS) {
  std::vector<msg::Goal> goals;
  std::string missing;
  auto goal = [&](const std::string& name, msg::GoalAction action, double duration, const std::string& load) {
    const Station* s = name.empty() ? nullptr : stations.find(name);
    if (s == nullptr) {
      // Never a goal at a made-up pose: the robot would drive to (0, 0) and report it reached.
      if (missing.empty()) {
        missing = name;
      }
      return;
    }
    goals.push_back({s->pose, name, action, duration, load});
  };
  switch (t.kind) {
    case TaskKind::Transport:
      goal(t.pickup, msg::GoalAction::Load, nsToSec(t.loadNs), "");
      goal(t.dropoff, msg::GoalAction::Unload, nsToSec(t.unloadNs), "");
      break;
    case TaskKind::Goto:
      goal(t.station, msg::GoalAction::None, 0, "");
      break;
    case TaskKind::Charge:
      // Dwell until the manager ends the task (battery at charge_until), at most charge_max_s.
      goal(t.station, msg::GoalAction::Charge, chargeMaxS, "");
      break;
    case TaskKind::Park:
      goal(t.station, msg::GoalAction::Park, 0, "");
      break;
    case TaskKind::Multistop:
      for (const auto& s : t.steps) {
        double dwell = nsToSec(s.durationNs);
        if (s.action == StepAction::Charge && s.durationNs == 0) {
          dwell = chargeMaxS;
        }
        if (s.action == StepAction::Wait && s.station.empty() && !goals.empty()) {
          // Waits where the stop before it ended: a goal at that stop, reached at once.
          auto here = goals.back();
          goals.push_back({here.pose, here.station, msg::GoalAction::None, dwell, ""});
          continue;
        }
        goal(s.station, actionOf(s.action), dwell, s.loadId);
      }
      break;
  }
  if (goals.empty() || !missing.empty()) {
    return unexpected(errc::kInternal,
                      "task '" + t.id + "' has " +
                          (missing.empty() ? std::string("no station")
                                           : "station '" + missing + "', which is not on this site"));
  }
  return goals;
}

}  // namespace fleet::manager
