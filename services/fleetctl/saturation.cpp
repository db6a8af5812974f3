#include "saturation.hpp"

#include "round3.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <unordered_map>
#include <unordered_set>

namespace fleet::ctl {

SaturatedWindow saturatedWindow(const std::vector<TransitionRow>& transitions, std::size_t robots,
                                double endS) {
  SaturatedWindow w;
  w.robots = robots;
  if (robots == 0) {
    return w;
  }
  // The waiting count as a step function of time. Several transitions can share a stamp (the
  // manager assigns a batch in one tick): the count is taken after the last of them.
  std::unordered_map<std::string, bool> queued;
  std::size_t waiting = 0;
  double openedAt = -1.0;  // start of the current stretch with waiting ≥ robots, or < 0
  double heldS = 0.0;
  bool any = false;
  auto settle = [&](double t) {
    w.peakWaiting = std::max(w.peakWaiting, waiting);
    const bool holds = waiting >= robots;
    if (holds && openedAt < 0.0) {
      openedAt = t;
      if (!any) {
        w.fromS = t;
        any = true;
      }
    } else if (!holds && openedAt >= 0.0) {
      heldS += t - openedAt;
      w.toS = t;
      openedAt = -1.0;
    }
  };
  for (std::size_t i = 0; i < transitions.size(); ++i) {
    const auto& tr = transitions[i];
    bool& q = queued[tr.taskId];
    const bool nowQueued = tr.toState == "queued";
    if (nowQueued && !q) {
      ++waiting;
    } else if (!nowQueued && q) {
      --waiting;
    }
    q = nowQueued;
    const double t = static_cast<double>(tr.stampNs) * 1e-9;
    if (i + 1 == transitions.size() || transitions[i + 1].stampNs != tr.stampNs) {
      settle(t);
    }
  }
  if (openedAt >= 0.0) {
    const double end = std::max(endS, openedAt);
    heldS += end - openedAt;
    w.toS = end;
  }
  if (!any || w.toS <= w.fromS) {
    return w;
  }
  w.found = true;
  w.heldFraction = heldS / (w.toS - w.fromS);
  std::unordered_set<std::string> finished;
  for (const auto& tr : transitions) {
    const double t = static_cast<double>(tr.stampNs) * 1e-9;
    if (tr.toState == "done" && finished.insert(tr.taskId).second && t > w.fromS && t <= w.toS) {
      ++w.done;
    }
  }
  w.perRobotPerH = static_cast<double>(w.done) / static_cast<double>(robots) * 3600.0 / (w.toS - w.fromS);
  return w;
}

nlohmann::json saturatedJson(const SaturatedWindow& w) {
  nlohmann::json j = {{"found", w.found},
                      {"definition",
                       "from the first to the last instant at which at least as many tasks waited "
                       "(stored, not assigned) as there were robots"},
                      {"robots", w.robots},
                      {"peak_waiting", w.peakWaiting}};
  if (!w.found) {
    j["why"] = "never as many tasks waiting as robots for any length of time";
    return j;
  }
  j["from_s"] = round3(w.fromS);
  j["to_s"] = round3(w.toS);
  j["held_fraction"] = round3(w.heldFraction);
  j["done"] = w.done;
  j["fleet_rate_per_h"] = round3(w.perRobotPerH * static_cast<double>(w.robots));
  j["per_robot_rate_per_h"] = round3(w.perRobotPerH);
  return j;
}

std::string saturatedLine(const nlohmann::json& s) {
  if (!s.value("found", false)) {
    return "saturated window: none (" + s.value("why", std::string("?")) + "; peak " +
           std::to_string(s.value("peak_waiting", 0)) + " waiting for " +
           std::to_string(s.value("robots", 0)) + " robots)";
  }
  char line[320];
  std::snprintf(
      line, sizeof line,
      "saturated window %.0f-%.0f s (held %.0f %% of it): %d done, %.1f tasks/h, %.2f per robot-hour",
      s.value("from_s", 0.0), s.value("to_s", 0.0), 100.0 * s.value("held_fraction", 0.0), s.value("done", 0),
      s.value("fleet_rate_per_h", 0.0), s.value("per_robot_rate_per_h", 0.0));
  return line;
}

}  // namespace fleet::ctl
