// Copies of the task messages (Task, TaskAck, TaskEvent, TaskAssignment, TaskStatus) between the
// C++ messages and the idlc-generated C structs.

#include <algorithm>

#include "convert_detail.hpp"

namespace fleet::transport {

using namespace convert_detail;  // the helpers this file shares with the other conversions

// ---- Task
void Traits<msg::Task>::toC(const msg::Task& in, C& out, Arena& arena) {
  putStr(out.task_id, in.task_id, "Task.task_id");
  putStr(out.request_id, in.request_id, "Task.request_id");
  out.kind = static_cast<fleet_TaskKind>(in.kind);
  putStr(out.pickup, in.pickup, "Task.pickup");
  putStr(out.dropoff, in.dropoff, "Task.dropoff");
  putStr(out.station, in.station, "Task.station");
  putStr(out.robot, in.robot, "Task.robot");
  out.load_ns = in.load_ns;
  out.unload_ns = in.unload_ns;
  out.priority = in.priority;
  out.deadline_ns = in.deadline_ns;
  out.created_ns = in.created_ns;
  out.cancel = in.cancel;
  out.control = static_cast<fleet_TaskControl>(in.control);
  out.set_priority = in.set_priority;
  out.set_deadline = in.set_deadline;
  putSeq(out.steps, in.steps, 16, arena, "Task.steps", [](const msg::TaskStep& st, fleet_TaskStep& c) {
    c.action = static_cast<fleet_StepAction>(st.action);
    putStr(c.station, st.station, "Task.steps[].station");
    putStr(c.load_id, st.load_id, "Task.steps[].load_id");
    c.duration_ns = st.duration_ns;
  });
}
msg::Task Traits<msg::Task>::fromC(const C& in) {
  msg::Task m;
  m.task_id = getStr(in.task_id);
  m.request_id = getStr(in.request_id);
  m.kind = getEnum(in.kind, msg::TaskKind::Multistop);
  m.pickup = getStr(in.pickup);
  m.dropoff = getStr(in.dropoff);
  m.station = getStr(in.station);
  m.robot = getStr(in.robot);
  m.load_ns = in.load_ns;
  m.unload_ns = in.unload_ns;
  m.priority = in.priority;
  m.deadline_ns = in.deadline_ns;
  m.created_ns = in.created_ns;
  m.cancel = in.cancel;
  m.control = getEnum(in.control, msg::TaskControl::Change);
  m.set_priority = in.set_priority;
  m.set_deadline = in.set_deadline;
  m.steps = getSeq(in.steps, [](const fleet_TaskStep& c) {
    return msg::TaskStep{getEnum(c.action, msg::StepAction::Charge), getStr(c.station), getStr(c.load_id),
                         c.duration_ns};
  });
  return m;
}

// ---- TaskAck
void Traits<msg::TaskAck>::toC(const msg::TaskAck& in, C& out, Arena&) {
  putStr(out.request_id, in.request_id, "TaskAck.request_id");
  putStr(out.task_id, in.task_id, "TaskAck.task_id");
  out.result = static_cast<fleet_AckResult>(in.result);
  out.state = static_cast<fleet_TaskState>(in.state);
  putStr(out.detail, in.detail, "TaskAck.detail");
  out.stamp_ns = in.stamp_ns;
}
msg::TaskAck Traits<msg::TaskAck>::fromC(const C& in) {
  return {getStr(in.request_id),
          getStr(in.task_id),
          getEnum(in.result, msg::AckResult::Unavailable),
          getEnum(in.state, msg::TaskState::Rejected),
          getStr(in.detail),
          in.stamp_ns};
}

// ---- TaskEvent
void Traits<msg::TaskEvent>::toC(const msg::TaskEvent& in, C& out, Arena&) {
  putStr(out.task_id, in.task_id, "TaskEvent.task_id");
  out.state = static_cast<fleet_TaskState>(in.state);
  putStr(out.robot_id, in.robot_id, "TaskEvent.robot_id");
  putStr(out.reason, in.reason, "TaskEvent.reason");
  out.stamp_ns = in.stamp_ns;
  out.seq = in.seq;
  putStr(out.station, in.station, "TaskEvent.station");
  out.changed = in.changed;
  out.priority = in.priority;
  out.deadline_ns = in.deadline_ns;
  out.eta_ns = in.eta_ns;
  out.epoch = in.epoch;
  out.step = in.step;
}
msg::TaskEvent Traits<msg::TaskEvent>::fromC(const C& in) {
  return {getStr(in.task_id),
          getEnum(in.state, msg::TaskState::Rejected),
          getStr(in.robot_id),
          getStr(in.reason),
          in.stamp_ns,
          in.seq,
          getStr(in.station),
          in.changed,
          in.priority,
          in.deadline_ns,
          in.eta_ns,
          in.epoch,
          in.step};
}

// ---- TaskAssignment
void Traits<msg::TaskAssignment>::toC(const msg::TaskAssignment& in, C& out, Arena& arena) {
  putStr(out.robot_id, in.robot_id, "TaskAssignment.robot_id");
  putStr(out.task_id, in.task_id, "TaskAssignment.task_id");
  out.revision = in.revision;
  putSeq(out.goals, in.goals, 16, arena, "TaskAssignment.goals", [](const msg::Goal& g, fleet_Goal& c) {
    c.pose = putPose(g.pose);
    putStr(c.station, g.station, "TaskAssignment.goals[].station");
    c.action = static_cast<fleet_GoalAction>(g.action);
    c.duration_s = g.duration_s;
  });
  out.paused = in.paused;
  out.stamp_ns = in.stamp_ns;
  out.priority = in.priority;
  out.epoch = in.epoch;
  // One id per goal, or none at all when no goal carries a load.
  const bool loads =
      std::any_of(in.goals.begin(), in.goals.end(), [](const msg::Goal& g) { return !g.load_id.empty(); });
  const std::size_t n = loads ? in.goals.size() : 0;
  // fleet_Id is a char array, which the arena cannot allocate as an element type: bytes instead.
  auto* ids = n == 0 ? nullptr : reinterpret_cast<fleet_Id*>(arena.alloc<char>(n * sizeof(fleet_Id)));
  for (std::size_t i = 0; i < n; ++i) {
    putStr(ids[i], in.goals[i].load_id, "TaskAssignment.goals[].load_id");
  }
  out.goal_load_ids._buffer = ids;
  out.goal_load_ids._length = static_cast<std::uint32_t>(n);
  out.goal_load_ids._maximum = static_cast<std::uint32_t>(n);
  out.goal_load_ids._release = false;
}
msg::TaskAssignment Traits<msg::TaskAssignment>::fromC(const C& in) {
  msg::TaskAssignment m;
  m.robot_id = getStr(in.robot_id);
  m.task_id = getStr(in.task_id);
  m.revision = in.revision;
  m.goals = getSeq(in.goals, [](const fleet_Goal& c) {
    return msg::Goal{getPose(c.pose), getStr(c.station), getEnum(c.action, msg::GoalAction::Park),
                     c.duration_s};
  });
  m.paused = in.paused;
  m.stamp_ns = in.stamp_ns;
  m.priority = in.priority;
  m.epoch = in.epoch;
  // Ids past the goals (a sender's mistake) have no goal to go with and are left out.
  for (std::uint32_t i = 0; i < in.goal_load_ids._length && i < m.goals.size(); ++i) {
    m.goals[i].load_id = getStr(in.goal_load_ids._buffer[i]);
  }
  return m;
}

// ---- TaskStatus
void Traits<msg::TaskStatus>::toC(const msg::TaskStatus& in, C& out, Arena&) {
  putStr(out.robot_id, in.robot_id, "TaskStatus.robot_id");
  putStr(out.task_id, in.task_id, "TaskStatus.task_id");
  out.revision = in.revision;
  out.state = static_cast<fleet_TaskState>(in.state);
  out.progress = in.progress;
  putStr(out.error, in.error, "TaskStatus.error");
  out.stamp_ns = in.stamp_ns;
  out.step = in.step;
}
msg::TaskStatus Traits<msg::TaskStatus>::fromC(const C& in) {
  return {getStr(in.robot_id), getStr(in.task_id), in.revision, getEnum(in.state, msg::TaskState::Rejected),
          in.progress,         getStr(in.error),   in.stamp_ns, in.step};
}

}  // namespace fleet::transport
