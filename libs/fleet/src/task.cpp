#include "fleet/fleet/task.hpp"

#include "fleet/core/config.hpp"

#include <limits>
#include <set>

#include "fleet/core/ids.hpp"
#include "fleet/fleet/errors.hpp"
#include "fleet/fleet/station_map.hpp"
#include "task_detail.hpp"

namespace fleet {
namespace task_detail {

std::string join(std::string_view prefix, std::string_view field) {
  if (prefix.empty()) {
    return std::string(field);
  }
  return std::string(prefix) + "." + std::string(field);
}

void checkStation(const std::string& name, std::string_view path, StationKind need,
                  const StationMap* stations, std::vector<FieldError>& out) {
  if (!isValidId(name)) {
    out.push_back({std::string(path), "not a valid station id (1-63 characters of A-Z a-z 0-9 _ . : -)"});
    return;
  }
  if (stations == nullptr) {
    return;
  }
  const Station* s = stations->find(name);
  if (s == nullptr) {
    out.push_back({std::string(path), "unknown station '" + name + "'"});
  } else if (!s->has(need)) {
    out.push_back(
        {std::string(path), "station '" + name + "' is not a " + std::string(toString(need)) + " station"});
  }
}

}  // namespace task_detail

namespace {

using task_detail::checkStation;
using task_detail::join;

void forbid(bool present, std::string_view prefix, std::string_view field, TaskKind kind,
            std::vector<FieldError>& out) {
  if (present) {
    out.push_back({join(prefix, field), "not allowed for a " + std::string(toString(kind)) + " task"});
  }
}

}  // namespace

ValidationError makeValidationError(std::vector<FieldError> fields) {
  ValidationError e;
  for (const auto& f : fields) {
    e.message +=
        (e.message.empty() ? "" : "; ") + (f.path.empty() ? std::string("(body)") : f.path) + ": " + f.reason;
  }
  e.fields = std::move(fields);
  return e;
}

std::vector<FieldError> validateTask(const Task& t, const StationMap* stations, std::string_view prefix) {
  std::vector<FieldError> out;
  if (!isValidId(t.id)) {
    out.push_back({join(prefix, "id"), "not a valid id (1-63 characters of A-Z a-z 0-9 _ . : -)"});
  }
  if (!t.robot.empty() && !isValidId(t.robot)) {
    out.push_back({join(prefix, "robot"), "not a valid robot id"});
  }
  if (t.priority < kMinPriority || t.priority > kMaxPriority) {
    out.push_back({join(prefix, "priority"), "must be in [" + std::to_string(kMinPriority) + ", " +
                                                 std::to_string(kMaxPriority) + "]"});
  }
  if (t.deadlineNs < 0) {
    out.push_back({join(prefix, "deadline_ns"), "must be >= 0 (0 = no deadline)"});
  }
  if (t.createdNs < 0) {
    out.push_back({join(prefix, "created_ns"), "must be >= 0"});
  }
  if (t.deadlineNs > 0 && t.createdNs > 0 && t.deadlineNs < t.createdNs) {
    out.push_back({join(prefix, "deadline_ns"), "is before created_ns"});
  }
  if (t.kind != TaskKind::Multistop) {
    forbid(!t.steps.empty(), prefix, "steps", t.kind, out);
  }
  if (t.kind == TaskKind::Multistop) {
    forbid(!t.pickup.empty(), prefix, "pickup", t.kind, out);
    forbid(!t.dropoff.empty(), prefix, "dropoff", t.kind, out);
    forbid(!t.station.empty(), prefix, "station", t.kind, out);
    forbid(t.loadNs != 0, prefix, "load_duration_ns", t.kind, out);
    forbid(t.unloadNs != 0, prefix, "unload_duration_ns", t.kind, out);
    task_detail::validateSteps(t, stations, prefix, out);
  } else if (t.kind == TaskKind::Transport) {
    if (t.pickup.empty()) {
      out.push_back({join(prefix, "pickup"), "required for a transport task"});
    } else {
      checkStation(t.pickup, join(prefix, "pickup"), StationKind::Pickup, stations, out);
    }
    if (t.dropoff.empty()) {
      out.push_back({join(prefix, "dropoff"), "required for a transport task"});
    } else {
      checkStation(t.dropoff, join(prefix, "dropoff"), StationKind::Dropoff, stations, out);
      if (t.dropoff == t.pickup) {
        out.push_back({join(prefix, "dropoff"), "must differ from pickup"});
      }
    }
    forbid(!t.station.empty(), prefix, "station", t.kind, out);
    for (auto [v, name] :
         {std::pair{t.loadNs, "load_duration_ns"}, std::pair{t.unloadNs, "unload_duration_ns"}}) {
      if (v < 0 || v > kMaxHandlingNs) {
        out.push_back({join(prefix, name), "must be in [0, 3600e9] ns"});
      }
    }
  } else {
    forbid(!t.pickup.empty(), prefix, "pickup", t.kind, out);
    forbid(!t.dropoff.empty(), prefix, "dropoff", t.kind, out);
    forbid(t.loadNs != 0, prefix, "load_duration_ns", t.kind, out);
    forbid(t.unloadNs != 0, prefix, "unload_duration_ns", t.kind, out);
    if (t.station.empty()) {
      if (t.kind == TaskKind::Goto) {
        out.push_back({join(prefix, "station"), "required for a goto task"});
      } else if (stations != nullptr) {
        // The dispatcher picks the station at assignment; with none of the kind it never could,
        // and the task would wait for ever.
        const StationKind need = t.kind == TaskKind::Charge ? StationKind::Charging : StationKind::Parking;
        if (stations->ofKind(need).empty()) {
          out.push_back({join(prefix, "station"),
                         "no " + std::string(toString(need)) + " station on this site to choose from"});
        }
      }
    } else if (t.kind == TaskKind::Goto) {
      // Any station is a valid go-to target; only existence is checked.
      if (!isValidId(t.station)) {
        out.push_back(
            {join(prefix, "station"), "not a valid station id (1-63 characters of A-Z a-z 0-9 _ . : -)"});
      } else if (stations != nullptr && stations->find(t.station) == nullptr) {
        out.push_back({join(prefix, "station"), "unknown station '" + t.station + "'"});
      }
    } else {
      checkStation(t.station, join(prefix, "station"),
                   t.kind == TaskKind::Charge ? StationKind::Charging : StationKind::Parking, stations, out);
    }
  }
  return out;
}

Expected<Task, ValidationError> parseTask(const nlohmann::json& j, const StationMap* stations,
                                          std::string_view prefix) {
  std::vector<FieldError> errs;
  if (!j.is_object()) {
    errs.push_back({std::string(prefix), "expected a task object, got " + jsonTypeName(j)});
    return unexpected(makeValidationError(std::move(errs)));
  }
  static const std::set<std::string, std::less<>> kKnown = {
      "id",       "kind",        "pickup",           "dropoff",
      "station",  "robot",       "load_duration_ns", "unload_duration_ns",
      "priority", "deadline_ns", "created_ns",       "steps"};
  for (const auto& [key, value] : j.items()) {
    if (!kKnown.contains(key)) {
      errs.push_back({join(prefix, key), "unknown field"});
    }
  }
  Task t;
  bool typesOk = true;
  auto str = [&](const char* key, std::string& dst, bool required) {
    auto it = j.find(key);
    if (it == j.end()) {
      if (required) {
        errs.push_back({join(prefix, key), "required"});
        typesOk = false;
      }
      return;
    }
    if (!it->is_string()) {
      errs.push_back({join(prefix, key), "expected a string, got " + jsonTypeName(*it)});
      typesOk = false;
      return;
    }
    dst = it->get<std::string>();
    if (dst.empty()) {
      errs.push_back({join(prefix, key), "must not be empty"});
      typesOk = false;
    }
  };
  auto integer = [&](const char* key, std::int64_t& dst, std::int64_t lo, std::int64_t hi) {
    auto it = j.find(key);
    if (it == j.end()) {
      return;
    }
    if (it->is_number_unsigned()) {
      const auto v = it->get<std::uint64_t>();
      if (v > static_cast<std::uint64_t>(hi)) {
        errs.push_back(
            {join(prefix, key), "must be in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]"});
        typesOk = false;
        return;
      }
      dst = static_cast<std::int64_t>(v);
    } else if (it->is_number_integer()) {
      dst = it->get<std::int64_t>();
    } else {
      errs.push_back({join(prefix, key), "expected an integer, got " + jsonTypeName(*it)});
      typesOk = false;
      return;
    }
    if (dst < lo || dst > hi) {
      errs.push_back(
          {join(prefix, key), "must be in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]"});
      typesOk = false;
    }
  };
  str("id", t.id, true);
  std::string kind;
  // With steps the kind may be left out: such a task is a multi-stop task.
  str("kind", kind, !j.contains("steps"));
  if (!j.contains("kind") && j.contains("steps")) {
    t.kind = TaskKind::Multistop;
  }
  if (!kind.empty()) {
    if (auto k = parseTaskKind(kind)) {
      t.kind = *k;
    } else {
      errs.push_back({join(prefix, "kind"),
                      "unknown kind '" + kind + "' (expected transport, goto, charge, park or multistop)"});
      typesOk = false;
    }
  }
  str("pickup", t.pickup, false);
  str("dropoff", t.dropoff, false);
  str("station", t.station, false);
  str("robot", t.robot, false);
  constexpr std::int64_t kMaxI64 = std::numeric_limits<std::int64_t>::max();
  integer("load_duration_ns", t.loadNs, 0, kMaxHandlingNs);
  integer("unload_duration_ns", t.unloadNs, 0, kMaxHandlingNs);
  std::int64_t prio = 0;
  integer("priority", prio, kMinPriority, kMaxPriority);
  t.priority = static_cast<std::int32_t>(prio);
  integer("deadline_ns", t.deadlineNs, 0, kMaxI64);
  integer("created_ns", t.createdNs, 0, kMaxI64);
  if (auto it = j.find("steps"); it != j.end() && !task_detail::parseSteps(*it, prefix, t, errs)) {
    typesOk = false;
  }
  if (typesOk) {
    auto more = validateTask(t, stations, prefix);
    errs.insert(errs.end(), more.begin(), more.end());
  }
  if (!errs.empty()) {
    return unexpected(makeValidationError(std::move(errs)));
  }
  return t;
}

Expected<std::vector<Task>, ValidationError> parseTasks(const nlohmann::json& body,
                                                        const StationMap* stations) {
  std::vector<Task> out;
  std::vector<FieldError> errs;
  const nlohmann::json* list = nullptr;
  std::string base;
  if (body.is_array()) {
    list = &body;
  } else if (body.is_object() && body.contains("tasks") && !body.contains("id")) {
    for (const auto& [key, value] : body.items()) {
      if (key != "tasks") {
        errs.push_back({key, "unknown field"});
      }
    }
    list = &body.at("tasks");
    base = "tasks";
    if (!list->is_array()) {
      errs.push_back({"tasks", "expected an array, got " + jsonTypeName(*list)});
      return unexpected(makeValidationError(std::move(errs)));
    }
  } else {
    auto one = parseTask(body, stations);
    if (!one) {
      return unexpected(one.error());
    }
    out.push_back(std::move(one).value());
    return out;
  }
  if (list->empty()) {
    errs.push_back({base, "no tasks"});
  }
  std::set<std::string, std::less<>> seen;
  for (std::size_t i = 0; i < list->size(); ++i) {
    const std::string p = base + "[" + std::to_string(i) + "]";
    auto t = parseTask((*list)[i], stations, p);
    if (!t) {
      errs.insert(errs.end(), t.error().fields.begin(), t.error().fields.end());
      continue;
    }
    if (!seen.insert(t->id).second) {
      errs.push_back({p + ".id", "duplicate id '" + t->id + "' in this batch"});
      continue;
    }
    out.push_back(std::move(t).value());
  }
  if (!errs.empty()) {
    return unexpected(makeValidationError(std::move(errs)));
  }
  return out;
}

nlohmann::json toJson(const Task& t) {
  nlohmann::json j;
  j["id"] = t.id;
  j["kind"] = std::string(toString(t.kind));
  auto putStr = [&](const char* key, const std::string& v) {
    if (!v.empty()) {
      j[key] = v;
    }
  };
  putStr("pickup", t.pickup);
  putStr("dropoff", t.dropoff);
  putStr("station", t.station);
  putStr("robot", t.robot);
  auto putInt = [&](const char* key, std::int64_t v) {
    if (v != 0) {
      j[key] = v;
    }
  };
  putInt("load_duration_ns", t.loadNs);
  putInt("unload_duration_ns", t.unloadNs);
  putInt("priority", t.priority);
  putInt("deadline_ns", t.deadlineNs);
  putInt("created_ns", t.createdNs);
  if (!t.steps.empty()) {
    j["steps"] = task_detail::stepsToJson(t.steps);
  }
  return j;
}

std::string canonicalBody(const Task& t) {
  auto j = toJson(t);
  j.erase("created_ns");
  return j.dump();  // nlohmann::json objects keep keys sorted, so the dump is canonical
}

}  // namespace fleet
