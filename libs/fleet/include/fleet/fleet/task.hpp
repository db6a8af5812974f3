#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "fleet/core/expected.hpp"
#include "fleet/fleet/task_state.hpp"

namespace fleet {

class StationMap;

inline constexpr std::int32_t kMinPriority = -1000;
inline constexpr std::int32_t kMaxPriority = 1000;
/// Longest load or unload time a task may ask for (one hour).
inline constexpr std::int64_t kMaxHandlingNs = 3600LL * 1'000'000'000LL;

/// Most stops one multi-stop task may have (TaskAssignment carries at most 16 goals).
inline constexpr std::size_t kMaxSteps = 16;

/// What a multi-stop task does at one stop. Wire names: goto, pick, drop, wait, charge.
enum class StepAction : std::uint8_t { Goto, Pick, Drop, Wait, Charge };

/// One stop of a multi-stop task. Pick needs a pickup station and a load id, drop a drop-off
/// station and the id of a load picked before it, charge a charging station, goto any station;
/// wait needs a duration and waits at its station, or without one where the step before ended.
struct TaskStep {
  StepAction action = StepAction::Goto;
  std::string station;
  std::string loadId;           ///< pick and drop only
  std::int64_t durationNs = 0;  ///< dwell: wait (required), pick, drop, charge (optional)
  bool operator==(const TaskStep&) const = default;
};

/// A unit of work. Transport: pickup → dropoff. Goto: drive to `station`. Charge / park: go to
/// `station`, or when it is empty to the charging / parking station the dispatcher picks when it
/// assigns the task (the nearest free one for that robot; the store keeps the choice). Multistop:
/// `steps` in order (each stop a station visit); the other station fields stay empty.
struct Task {
  std::string id;
  TaskKind kind = TaskKind::Transport;
  std::string pickup;             ///< transport only
  std::string dropoff;            ///< transport only
  std::string station;            ///< goto (required), charge and park (optional)
  std::string robot;              ///< optional: only this robot may take the task
  std::int64_t loadNs = 0;        ///< transport only: time spent loading at the pickup
  std::int64_t unloadNs = 0;      ///< transport only: time spent unloading at the dropoff
  std::int32_t priority = 0;      ///< higher first, in [kMinPriority, kMaxPriority]
  std::int64_t deadlineNs = 0;    ///< 0 = none
  std::int64_t createdNs = 0;     ///< set by the intake when the client leaves it out
  std::vector<TaskStep> steps{};  ///< multistop only, 1..kMaxSteps

  bool operator==(const Task&) const = default;
};

/// One problem in a request: where (`tasks[2].pickup`) and why (`unknown station 'P-99'`).
struct FieldError {
  std::string path;
  std::string reason;
  bool operator==(const FieldError&) const = default;
};

/// Every problem found in a task document. `message` joins them for people; services return
/// `fields` as the body of a 400.
struct ValidationError {
  std::string code = "invalid";
  std::string message;
  std::vector<FieldError> fields;
};

/// Semantic checks on a task (ids, which fields each kind allows, ranges, and — when `stations` is
/// given — that every station exists and serves the purpose, and that a charge / park task without
/// a station has a station of its kind to be given). Paths are prefixed with `prefix`.
std::vector<FieldError> validateTask(const Task& t, const StationMap* stations = nullptr,
                                     std::string_view prefix = "");

/// Parses one task object: types, unknown fields, then validateTask. Wire field names are
/// id, kind, pickup, dropoff, station, robot, load_duration_ns, unload_duration_ns, priority,
/// deadline_ns, created_ns, steps (each {action, station, load_id, duration_ns}; with steps, kind
/// may be left out and is multistop). Step paths read `steps[2].station`.
Expected<Task, ValidationError> parseTask(const nlohmann::json& j, const StationMap* stations = nullptr,
                                          std::string_view prefix = "");
/// Parses a body holding one task object, an array of them, or `{"tasks": [...]}`; paths name the
/// element (`[3].kind` or `tasks[3].kind`). Duplicate ids inside one batch are an error.
Expected<std::vector<Task>, ValidationError> parseTasks(const nlohmann::json& body,
                                                        const StationMap* stations = nullptr);

/// The wire form; fields at their default value are left out.
nlohmann::json toJson(const Task& t);
/// The body that decides idempotency: toJson without created_ns (set by whoever received the
/// request first, so a retry would differ), serialized with sorted keys and no spaces. Two
/// requests with the same id are the same request exactly when their canonical bodies are equal.
std::string canonicalBody(const Task& t);

ValidationError makeValidationError(std::vector<FieldError> fields);

/// "goto", "pick", "drop", "wait", "charge".
std::string_view toString(StepAction a);
std::optional<StepAction> parseStepAction(std::string_view name);

/// The stations a task visits, in order, one entry a visit (a multi-stop task visiting a station
/// twice names it twice): pickup and dropoff, or the station, or each step's station. A wait
/// without a station is no visit. Empty for a charge / park task whose station is not chosen yet.
std::vector<const std::string*> taskStops(const Task& t);
/// The time a task asks to spend at its stops: load and unload, or its steps' durations.
std::int64_t taskDwellNs(const Task& t);

}  // namespace fleet
