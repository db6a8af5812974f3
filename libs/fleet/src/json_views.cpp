// JSON views of store records and robots, shared by the HTTP adapter and the CLI.
#include "fleet/fleet/robot_registry.hpp"
#include "fleet/fleet/task_store.hpp"

namespace fleet {

nlohmann::json toJson(const TaskRecord& r) {
  auto task = toJson(r.task);
  task["created_ns"] = r.task.createdNs;  // always present here, even when 0
  nlohmann::json j = {{"task", std::move(task)}, {"state", std::string(toString(r.state))},
                      {"robot", r.robotId},      {"attempts", r.attempts},
                      {"reason", r.reason},      {"updated_ns", r.updatedNs},
                      {"revision", r.revision},  {"paused", r.paused}};
  if (r.stationChosen) {
    j["station_chosen"] = true;
  }
  return j;
}

nlohmann::json toJson(const TransitionRecord& t) {
  return {{"seq", t.seq},
          {"task_id", t.taskId},
          {"from", t.from ? nlohmann::json(std::string(toString(*t.from))) : nlohmann::json(nullptr)},
          {"to", std::string(toString(t.to))},
          {"robot", t.robotId},
          {"reason", t.reason},
          {"stamp_ns", t.stampNs}};
}

nlohmann::json toJson(const RobotInfo& r) {
  return {{"id", r.id},           {"x", r.pose.x},
          {"y", r.pose.y},        {"theta", r.pose.theta},
          {"battery", r.battery}, {"last_seen_ns", r.lastSeenNs},
          {"lost", r.lost},       {"fault", r.fault},
          {"task", r.taskId}};
}

}  // namespace fleet
