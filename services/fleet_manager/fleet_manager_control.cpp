// FleetManagerNode::control: the requests on one task or robot that are not a submission (cancel,
// pause and resume, query, robot hold and release, change of priority and deadline).

#include "fleet_manager_node.hpp"
#include "manager_acks.hpp"

namespace fleet::manager {

using acks::ack;
using acks::fieldsJson;
using acks::refused;

void FleetManagerNode::control(const msg::Task& req, std::int64_t nowNs, Outbox& out) {
  if (req.cancel) {
    auto r = dispatcher_->cancel(req.task_id, "cancelled by request", nowNs);
    if (r) {
      out.acks.push_back(ack(req, msg::AckResult::Stored, msg::TaskState::Cancelled, "", nowNs));
      publish(std::move(*r), nowNs, out);
    } else {
      out.acks.push_back(refused(req, r.error(), nowNs));
    }
    return;
  }
  switch (req.control) {
    case msg::TaskControl::None:
      return;  // a submission: not here
    case msg::TaskControl::Query:
      out.acks.push_back(query(req, nowNs));
      return;
    case msg::TaskControl::Change:
      out.acks.push_back(change(req, nowNs, out));
      return;
    case msg::TaskControl::HoldRobot:
    case msg::TaskControl::ReleaseRobot: {
      const bool hold = req.control == msg::TaskControl::HoldRobot;
      auto r = dispatcher_->setRobotHeld(req.robot, hold, nowNs);
      if (r) {
        const RobotInfo* info = dispatcher_->robots().find(req.robot);
        out.acks.push_back(ack(req, msg::AckResult::Stored, msg::TaskState::Queued,
                               info != nullptr ? info->taskId : std::string(), nowNs));
        publish(std::move(*r), nowNs, out);
      } else {
        out.acks.push_back(refused(req, r.error(), nowNs));
      }
      return;
    }
    case msg::TaskControl::Pause:
    case msg::TaskControl::Resume: {
      const bool pause = req.control == msg::TaskControl::Pause;
      auto r = dispatcher_->setPaused(req.task_id, pause, nowNs);
      if (r) {
        const auto it = dispatcher_->openTasks().find(req.task_id);
        const auto state = it != dispatcher_->openTasks().end() ? it->second.state : msg::TaskState::Queued;
        out.acks.push_back(ack(req, msg::AckResult::Stored, state, pause ? "paused" : "resumed", nowNs));
        publish(std::move(*r), nowNs, out);
      } else {
        out.acks.push_back(refused(req, r.error(), nowNs));
      }
      return;
    }
  }
}

msg::TaskAck FleetManagerNode::change(const msg::Task& req, std::int64_t nowNs, Outbox& out) {
  ChangeRequest q;
  q.taskId = req.task_id;
  if (req.set_priority) {
    q.priority = req.priority;
  }
  if (req.set_deadline) {
    q.deadlineNs = req.deadline_ns;
  }
  q.stampNs = nowNs;
  std::vector<FieldError> fields;
  auto r = dispatcher_->change(q, &fields);
  if (!r) {
    const auto& code = r.error().code;
    if (!fields.empty() || code == errc::kInvalid) {
      // The store checks as the dispatcher does; should it refuse alone, its message is the field.
      return ack(req, msg::AckResult::Invalid, msg::TaskState::Rejected,
                 fieldsJson(fields.empty() ? std::vector<FieldError>{{"", r.error().message}} : fields),
                 nowNs);
    }
    if (code == errc::kIllegalTransition) {
      // The ack carries the state the task is in, for the adapter's 409 to name.
      const auto stored = store_->get(req.task_id);
      return refused(req, r.error(), nowNs, stored ? stored->state : msg::TaskState::Rejected);
    }
    if (code == errc::kNotFound) {
      return refused(req, r.error(), nowNs);
    }
    return ack(req, msg::AckResult::Unavailable, msg::TaskState::Rejected, r.error().message, nowNs);
  }
  const bool changed = !r->events.empty();
  publish(std::move(*r), nowNs, out);
  const auto it = dispatcher_->openTasks().find(req.task_id);
  if (it == dispatcher_->openTasks().end()) {
    return ack(req, msg::AckResult::Stored, msg::TaskState::Queued, "", nowNs);
  }
  const TaskRecord& rec = it->second;
  const nlohmann::json d = {{"priority", rec.task.priority},
                            {"deadline_ns", rec.task.deadlineNs},
                            {"changed", changed},
                            {"revision", rec.revision}};
  return ack(req, msg::AckResult::Stored, rec.state, d.dump(), nowNs);
}

msg::TaskAck FleetManagerNode::query(const msg::Task& req, std::int64_t nowNs) {
  auto r = store_->get(req.task_id);
  if (!r) {
    return refused(req, r.error(), nowNs);
  }
  nlohmann::json d = {{"robot", r->robotId},
                      {"reason", r->reason.substr(0, 255)},
                      {"updated_ns", r->updatedNs},
                      {"revision", r->revision},
                      {"task", toJson(r->task)}};
  if (r->stationChosen) {
    d["station_chosen"] = true;  // task.station was chosen by the dispatcher, not sent
  }
  const auto replace = nlohmann::json::error_handler_t::replace;
  std::string detail = d.dump(-1, ' ', false, replace);
  if (detail.size() > 1023) {
    d.erase("task");  // the state matters; the body is a nicety
    detail = d.dump(-1, ' ', false, replace);
  }
  return ack(req, msg::AckResult::Stored, r->state, std::move(detail), nowNs);
}

}  // namespace fleet::manager
