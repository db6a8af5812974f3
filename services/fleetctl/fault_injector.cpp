#include "fault_injector.hpp"

#include <signal.h>

namespace fleet::ctl {

using nlohmann::json;

FaultInjector::FaultInjector(std::vector<Fault> faults, std::map<std::string, std::string> agentOfRobot,
                             bool standbyManagers, FaultActions& actions, Say say)
    : faults_(std::move(faults)),
      agentOfRobot_(std::move(agentOfRobot)),
      standby_(standbyManagers),
      act_(actions),
      say_(std::move(say)),
      started_(faults_.size(), false),
      ended_(faults_.size(), false),
      endAt_(faults_.size(), Clock::now()),
      target_(faults_.size()) {}

void FaultInjector::note(double simS, const std::string& what) {
  log_.push_back({{"sim_s", simS}, {"event", what}});
  say_("fault: " + what);
}

std::string FaultInjector::agentFor(const Fault& f) const {
  if (f.kind == Fault::Kind::StallRobot) {
    auto it = agentOfRobot_.find(f.robot);
    return it == agentOfRobot_.end() ? "" : it->second;
  }
  return "agent-" + std::to_string(f.agent);
}

void FaultInjector::apply(double simS, Clock::time_point now) {
  for (std::size_t i = 0; i < faults_.size(); ++i) {
    switch (faults_[i].kind) {
      case Fault::Kind::DropDds:
        break;  // every process drops packets from the start (its Cyclone configuration)
      case Fault::Kind::HideLandmarks:
        applyLandmarks(i, simS);
        break;
      case Fault::Kind::CloseArea:
        applyClosure(i, simS);
        break;
      default:
        applyProcess(i, simS, now);
    }
  }
}

void FaultInjector::applyLandmarks(std::size_t i, double simS) {
  // The simulator hides them on its own clock (--hide-landmarks): only logged here.
  const Fault& f = faults_[i];
  if (!started_[i] && simS >= f.atS) {
    started_[i] = true;
    note(simS, "landmarks hidden (fleet-sim) for " + std::to_string(static_cast<int>(f.downS)) + " s");
  } else if (started_[i] && !ended_[i] && simS >= f.atS + f.downS) {
    ended_[i] = true;
    note(simS, "landmarks visible again");
  }
}

void FaultInjector::applyClosure(std::size_t i, double simS) {
  // Through the API an operator would use; on the simulated clock, as hide-landmarks.
  const Fault& f = faults_[i];
  const std::string path = "/v1/traffic/closures/fault-" + std::to_string(i);
  if (!started_[i] && simS >= f.atS) {
    started_[i] = true;
    json body = {{"area", json::array()}, {"reason", ("load test fault " + describe(f)).substr(0, 255)}};
    for (std::size_t k = 0; k + 1 < f.area.size(); k += 2) {
      body["area"].push_back({f.area[k], f.area[k + 1]});
    }
    note(simS, "closed area fault-" + std::to_string(i) + ": " + act_.putClosure(path, body));
  } else if (started_[i] && !ended_[i] && simS >= f.atS + f.downS) {
    ended_[i] = true;
    note(simS, "reopened area fault-" + std::to_string(i) + ": " + act_.deleteClosure(path));
  }
}

void FaultInjector::applyProcess(std::size_t i, double simS, Clock::time_point now) {
  const Fault& f = faults_[i];
  std::string& who = target_[i];
  if (!started_[i] && simS >= f.atS) {
    started_[i] = true;
    endAt_[i] = now + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(f.downS));
    who = killedService(f).empty() ? agentFor(f) : killedService(f);
    if (f.kind == Fault::Kind::StallRobot) {
      act_.signal(who, SIGSTOP);
      note(simS, "SIGSTOP " + who + " (robot " + f.robot + ")");
    } else if (f.kind == Fault::Kind::KillManager && standby_) {
      // Two managers: the active one is killed, the standby takes over (timed).
      who = act_.killActiveManager();
      note(simS,
           who.empty() ? std::string("no active fleet manager to kill") : "SIGKILL " + who + " (active)");
    } else {
      act_.kill(who);
      note(simS, "SIGKILL " + who);
    }
  } else if (started_[i] && !ended_[i] && now >= endAt_[i]) {
    ended_[i] = true;
    if (f.kind == Fault::Kind::StallRobot) {
      act_.signal(who, SIGCONT);
      note(simS, "SIGCONT " + who);
    } else if (!who.empty()) {
      act_.restart(who);
      note(simS, "restarted " + who);
    }
  }
}

int FaultInjector::endAll(double simS) {
  int restarted = 0;
  for (std::size_t i = 0; i < faults_.size(); ++i) {
    if (!started_[i] || ended_[i]) {
      continue;
    }
    const std::string& who = target_[i];
    const auto kind = faults_[i].kind;
    if (kind == Fault::Kind::StallRobot) {
      act_.signal(who, SIGCONT);
      note(simS, "SIGCONT " + who + " (end of run)");
    } else if (!who.empty() && (kind == Fault::Kind::KillManager || kind == Fault::Kind::KillTraffic)) {
      act_.restart(who);
      note(simS, "restarted " + who + " (end of run)");
      ++restarted;
    }
    ended_[i] = true;
  }
  return restarted;
}

}  // namespace fleet::ctl
