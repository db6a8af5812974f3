// The steps of a multi-stop task: parsed from and written to the wire form, checked against the
// site, and the stations the task visits.

#include <algorithm>
#include <array>
#include <map>
#include <set>

#include "fleet/core/config.hpp"
#include "fleet/core/ids.hpp"
#include "task_detail.hpp"

namespace fleet {
namespace {

constexpr std::array<std::string_view, 5> kActionNames = {"goto", "pick", "drop", "wait", "charge"};

std::string at(std::string_view prefix, std::size_t i) {
  return task_detail::join(prefix, "steps") + "[" + std::to_string(i) + "]";
}

std::string stepName(StepAction a) {
  return "a " + std::string(toString(a)) + " step";
}

/// The station a step of `action` must be (goto and wait: any station).
std::optional<StationKind> stationKindFor(StepAction a) {
  switch (a) {
    case StepAction::Pick:
      return StationKind::Pickup;
    case StepAction::Drop:
      return StationKind::Dropoff;
    case StepAction::Charge:
      return StationKind::Charging;
    case StepAction::Goto:
    case StepAction::Wait:
      break;
  }
  return std::nullopt;
}

void checkStepStation(const TaskStep& s, std::size_t i, const std::string& path, const StationMap* stations,
                      std::vector<FieldError>& out) {
  if (s.station.empty()) {
    if (s.action != StepAction::Wait) {
      out.push_back({path, "required for " + stepName(s.action)});
    } else if (i == 0) {
      out.push_back(
          {path, "required for a wait that is the first step (there is no stop before it to wait at)"});
    }
    return;
  }
  if (const auto need = stationKindFor(s.action)) {
    task_detail::checkStation(s.station, path, *need, stations, out);
  } else if (!isValidId(s.station)) {
    out.push_back({path, "not a valid station id (1-63 characters of A-Z a-z 0-9 _ . : -)"});
  } else if (stations != nullptr && stations->find(s.station) == nullptr) {
    out.push_back({path, "unknown station '" + s.station + "'"});
  }
}

}  // namespace

std::string_view toString(StepAction a) {
  return kActionNames.at(static_cast<std::size_t>(a));
}

std::optional<StepAction> parseStepAction(std::string_view name) {
  const auto it = std::find(kActionNames.begin(), kActionNames.end(), name);
  if (it == kActionNames.end()) {
    return std::nullopt;
  }
  return static_cast<StepAction>(it - kActionNames.begin());
}

std::vector<const std::string*> taskStops(const Task& t) {
  std::vector<const std::string*> s;
  for (const std::string* n : {&t.pickup, &t.dropoff, &t.station}) {
    if (!n->empty()) {
      s.push_back(n);
    }
  }
  for (const auto& step : t.steps) {
    if (!step.station.empty()) {
      s.push_back(&step.station);
    }
  }
  return s;
}

std::int64_t taskDwellNs(const Task& t) {
  std::int64_t ns = t.loadNs + t.unloadNs;
  for (const auto& s : t.steps) {
    ns += s.durationNs;
  }
  return ns;
}

namespace task_detail {

bool parseSteps(const nlohmann::json& steps, std::string_view prefix, Task& t, std::vector<FieldError>& out) {
  const std::string path = join(prefix, "steps");
  if (!steps.is_array()) {
    out.push_back({path, "expected an array of steps, got " + jsonTypeName(steps)});
    return false;
  }
  if (steps.size() > kMaxSteps) {
    // Checked before the elements: a huge array is refused without reading it.
    out.push_back(
        {path, "at most " + std::to_string(kMaxSteps) + " steps, got " + std::to_string(steps.size())});
    return false;
  }
  bool ok = true;
  for (std::size_t i = 0; i < steps.size(); ++i) {
    const auto& j = steps[i];
    const std::string p = at(prefix, i);
    TaskStep s;
    if (!j.is_object()) {
      out.push_back({p, "expected a step object, got " + jsonTypeName(j)});
      ok = false;
      continue;
    }
    for (const auto& [key, value] : j.items()) {
      if (key != "action" && key != "station" && key != "load_id" && key != "duration_ns") {
        out.push_back({p + "." + key, "unknown field"});
        ok = false;
      }
    }
    auto str = [&](const char* key, std::string& dst) {
      auto it = j.find(key);
      if (it == j.end()) {
        return true;
      }
      if (!it->is_string() || it->get_ref<const std::string&>().empty()) {
        out.push_back({p + "." + key, it->is_string() ? std::string("must not be empty")
                                                      : "expected a string, got " + jsonTypeName(*it)});
        return false;
      }
      dst = it->get<std::string>();
      return true;
    };
    std::string action;
    ok = str("action", action) && ok;
    if (!j.contains("action")) {
      out.push_back({p + ".action", "required (goto, pick, drop, wait or charge)"});
      ok = false;
    } else if (!action.empty()) {
      if (auto a = parseStepAction(action)) {
        s.action = *a;
      } else {
        out.push_back(
            {p + ".action", "unknown action '" + action + "' (expected goto, pick, drop, wait or charge)"});
        ok = false;
      }
    }
    ok = str("station", s.station) && ok;
    ok = str("load_id", s.loadId) && ok;
    if (auto it = j.find("duration_ns"); it != j.end()) {
      if (!it->is_number_integer() || (!it->is_number_unsigned() && it->get<std::int64_t>() < 0) ||
          (it->is_number_unsigned() &&
           it->get<std::uint64_t>() > static_cast<std::uint64_t>(kMaxHandlingNs))) {
        out.push_back({p + ".duration_ns", "must be an integer in [0, 3600e9] ns"});
        ok = false;
      } else {
        s.durationNs = it->get<std::int64_t>();
      }
    }
    t.steps.push_back(std::move(s));
  }
  return ok;
}

void validateSteps(const Task& t, const StationMap* stations, std::string_view prefix,
                   std::vector<FieldError>& out) {
  if (t.steps.empty()) {
    out.push_back({join(prefix, "steps"),
                   "required for a multistop task (1 to " + std::to_string(kMaxSteps) + " steps)"});
    return;
  }
  if (t.steps.size() > kMaxSteps) {
    out.push_back({join(prefix, "steps"),
                   "at most " + std::to_string(kMaxSteps) + " steps, got " + std::to_string(t.steps.size())});
    return;
  }
  std::map<std::string, std::size_t, std::less<>> held;  // load on the robot -> the step that picked it
  for (std::size_t i = 0; i < t.steps.size(); ++i) {
    const auto& s = t.steps[i];
    const std::string p = at(prefix, i);
    checkStepStation(s, i, p + ".station", stations, out);
    const bool carries = s.action == StepAction::Pick || s.action == StepAction::Drop;
    if (!carries && !s.loadId.empty()) {
      out.push_back({p + ".load_id", "not allowed for " + stepName(s.action)});
    } else if (carries && s.loadId.empty()) {
      out.push_back({p + ".load_id", "required for " + stepName(s.action)});
    } else if (carries && !isValidId(s.loadId)) {
      out.push_back({p + ".load_id", "not a valid load id (1-63 characters of A-Z a-z 0-9 _ . : -)"});
    } else if (s.action == StepAction::Pick && held.contains(s.loadId)) {
      out.push_back({p + ".load_id", "load '" + s.loadId + "' is already on the robot (picked at " +
                                         at(prefix, held.at(s.loadId)) + ")"});
    } else if (s.action == StepAction::Pick) {
      held.emplace(s.loadId, i);
    } else if (s.action == StepAction::Drop && held.erase(s.loadId) == 0) {
      out.push_back(
          {p + ".load_id", "load '" + s.loadId + "' is not on the robot here (no pick of it before)"});
    }
    if (s.durationNs < 0 || s.durationNs > kMaxHandlingNs) {
      out.push_back({p + ".duration_ns", "must be in [0, 3600e9] ns"});
    } else if (s.action == StepAction::Wait && s.durationNs == 0) {
      out.push_back({p + ".duration_ns", "required (> 0) for a wait step"});
    } else if (s.action == StepAction::Goto && s.durationNs != 0) {
      out.push_back({p + ".duration_ns", "not allowed for a goto step (add a wait step)"});
    }
  }
  for (const auto& [load, i] : held) {
    out.push_back({at(prefix, i) + ".load_id", "load '" + load + "' is picked but never dropped"});
  }
}

nlohmann::json stepsToJson(const std::vector<TaskStep>& steps) {
  auto out = nlohmann::json::array();
  for (const auto& s : steps) {
    nlohmann::json j;
    j["action"] = std::string(toString(s.action));
    if (!s.station.empty()) {
      j["station"] = s.station;
    }
    if (!s.loadId.empty()) {
      j["load_id"] = s.loadId;
    }
    if (s.durationNs != 0) {
      j["duration_ns"] = s.durationNs;
    }
    out.push_back(std::move(j));
  }
  return out;
}

}  // namespace task_detail
}  // namespace fleet
