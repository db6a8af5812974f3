#include "fleet/fleet/task_wire.hpp"

namespace fleet {

// The wire's kinds and step actions are the library's, in the same order (idl/fleet.idl TaskKind,
// StepAction).
msg::Task toWire(const Task& t, std::string requestId, std::int64_t nowNs) {
  msg::Task m;
  m.task_id = t.id;
  m.request_id = std::move(requestId);
  m.kind = static_cast<msg::TaskKind>(static_cast<int>(t.kind));
  m.pickup = t.pickup;
  m.dropoff = t.dropoff;
  m.station = t.station;
  m.robot = t.robot;
  m.load_ns = t.loadNs;
  m.unload_ns = t.unloadNs;
  m.priority = t.priority;
  m.deadline_ns = t.deadlineNs;
  m.created_ns = t.createdNs != 0 ? t.createdNs : nowNs;
  for (const auto& s : t.steps) {
    m.steps.push_back(
        {static_cast<msg::StepAction>(static_cast<int>(s.action)), s.station, s.loadId, s.durationNs});
  }
  return m;
}

Task fromWire(const msg::Task& m, std::int64_t nowNs) {
  Task t;
  t.id = m.task_id;
  t.kind = static_cast<TaskKind>(static_cast<int>(m.kind));
  t.pickup = m.pickup;
  t.dropoff = m.dropoff;
  t.station = m.station;
  t.robot = m.robot;
  t.loadNs = m.load_ns;
  t.unloadNs = m.unload_ns;
  t.priority = m.priority;
  t.deadlineNs = m.deadline_ns;
  t.createdNs = m.created_ns != 0 ? m.created_ns : nowNs;
  for (const auto& s : m.steps) {
    t.steps.push_back(
        {static_cast<StepAction>(static_cast<int>(s.action)), s.station, s.load_id, s.duration_ns});
  }
  return t;
}

}  // namespace fleet
