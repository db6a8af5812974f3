#include "bridge_node.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "fleet/vda5050/header.hpp"
#include "fleet/vda5050/instant_actions.hpp"
#include "vehicle_state.hpp"

namespace fleet::vdabridge {

using bridge_detail::baseAhead;
using bridge_detail::findAction;
using vda5050::VehicleHealth;

BridgeNode::BridgeNode(BridgeSettings settings)
    : settings_(std::move(settings)),
      registry_(settings_.interface_name, settings_.map_id, settings_.vehicles,
                vda5050::RegistryLimits{.maxMessageBytes = settings_.max_message_bytes}) {
  for (const auto& e : settings_.vehicles) {
    vehicles_.emplace(e.robot_id,
                      Vehicle(e, vda5050::OrderBuilder({e.manufacturer, e.serial, settings_.map_id,
                                                        settings_.allowed_deviation})));
  }
}

std::string BridgeNode::goalActionId(const Vehicle& v, std::size_t goal) const {
  return v.task_id + "-g" + std::to_string(goal);
}

void BridgeNode::onMqtt(const std::string& topic, const std::string& payload, BridgeOutbox& out) {
  const auto r = registry_.onMessage(topic, payload);
  if (!r.accepted && !r.reason.empty()) {
    ++counters_.refused_messages;
    out.warnings.push_back((r.robot_id.empty() ? std::string("?") : r.robot_id) + ": refused: " + r.reason);
  }
  if (r.health_changed) {
    const auto* v = registry_.find(r.robot_id);
    out.warnings.push_back(r.robot_id + ": " + vda5050::toString(v->health) +
                           (v->reason.empty() ? std::string() : " (" + v->reason + ")"));
  }
}

void BridgeNode::instant(Vehicle& v, const std::string& type, std::int64_t nowNs, BridgeOutbox& out,
                         const std::string& id) {
  vda5050::InstantActions ia;
  ia.header = {v.instant_header++, vda5050::isoTimestamp(nowNs), vda5050::kVersion, v.entry.manufacturer,
               v.entry.serial};
  ia.actions.push_back(
      {type, id.empty() ? type + "-" + std::to_string(ia.header.headerId) : id, "HARD", {}, {}});
  out.mqtt.push_back(
      {vda5050::topicName(settings_.interface_name, v.entry.manufacturer, v.entry.serial, "instantActions"),
       vda5050::toJson(ia).dump(), 0, false});
}

void BridgeNode::sendOrder(Vehicle& v, const vda5050::Order& o, std::int64_t nowNs, BridgeOutbox& out) {
  registry_.ordered(v.entry.robot_id, o);
  v.awaiting = true;
  v.sent_update = o.orderUpdateId;
  v.sent_ns = nowNs;
  out.mqtt.push_back(
      {vda5050::topicName(settings_.interface_name, v.entry.manufacturer, v.entry.serial, "order"),
       vda5050::toJson(o).dump(), 0, false});
  ++(o.orderUpdateId == 0 ? counters_.orders : counters_.updates);
}

void BridgeNode::onAssignment(const msg::TaskAssignment& a, std::int64_t nowNs, BridgeOutbox& out) {
  if (!managerEpoch_.admit(a.epoch)) {
    ++counters_.stale_epoch;  // from a manager whose lease has passed to another: never acted on
    return;
  }
  auto it = vehicles_.find(a.robot_id);
  if (it == vehicles_.end()) {
    return;
  }
  auto& v = it->second;
  // The same task again in a newer revision after it failed here: the manager re-queued it and
  // gave it back, so it starts afresh (a charge task at the same charger tries startCharging again).
  const bool retried = a.task_id == v.task_id && !v.failure.empty() && a.revision != v.revision;
  if (a.task_id != v.task_id || retried) {
    // A task taken away: stop where it is. A new task simply goes on with the current order: the
    // traffic manager's next releases extend it towards the new goal.
    if (a.task_id.empty() && !v.task_id.empty() && v.has_order) {
      instant(v, "cancelOrder", nowNs, out);
      ++counters_.cancels;
      v.has_order = false;
    }
    v.task_id = a.task_id;
    v.goal = 0;
    v.charge_action.clear();
    v.charge_arrived_ns = -1;
    v.charge_attempts = 0;
    v.dwell_since_ns = -1;
    v.failure.clear();
    freshChance(v);
    v.reported = msg::TaskState::Queued;
    v.reported_goal = 0;
  }
  v.revision = a.revision;
  v.priority = a.task_id.empty() ? 0 : a.priority;
  v.goals = a.goals;
  if (a.paused != v.paused) {
    v.paused = a.paused;
    instant(v, a.paused ? "startPause" : "stopPause", nowNs, out);
  }
  reportTask(v, nowNs, out);
}

void BridgeNode::onRelease(const msg::TrafficRelease& r) {
  auto it = vehicles_.find(r.robot_id);
  if (it == vehicles_.end()) {
    return;
  }
  auto& v = it->second;
  if (!v.release || v.release->base != r.base) {
    freshChance(v);
  }
  v.release = r;
  // Consecutive nodes of a release are joined by a roadmap edge in that direction: enough to start
  // an order at the vehicle's last node before the traffic manager's roadmap has arrived.
  const msg::RouteNode* prev = nullptr;
  for (const auto* part : {&r.base, &r.horizon}) {
    for (const auto& n : *part) {
      roadmap_.addNode({n.node, n.x, n.y});
      if (prev != nullptr) {
        roadmap_.addEdge(prev->node, n.node);
      }
      prev = &n;
    }
  }
}

void BridgeNode::onRoadmap(const msg::Roadmap& m) {
  roadmap_radius_ = m.robot_radius;
  roadmap_.clear();
  double minX = 0;
  double minY = 0;
  double maxX = 0;
  double maxY = 0;
  for (std::size_t i = 0; i < m.nodes.size(); ++i) {
    const auto& n = m.nodes[i];
    roadmap_.addNode({n.node, n.x, n.y});
    minX = i == 0 ? n.x : std::min(minX, n.x);
    minY = i == 0 ? n.y : std::min(minY, n.y);
    maxX = i == 0 ? n.x : std::max(maxX, n.x);
    maxY = i == 0 ? n.y : std::max(maxY, n.y);
  }
  if (!m.nodes.empty()) {
    // A vehicle is on the site: within the roadmap's extent and a margin (stations off the lanes).
    const double g = settings_.site_margin;
    registry_.setSiteBounds(minX - g, minY - g, maxX + g, maxY + g);
  }
  for (const auto& e : m.edges) {
    if (e.open) {
      roadmap_.addEdge(e.from, e.to);
    }
  }
}
void BridgeNode::reportTask(Vehicle& v, std::int64_t nowNs, BridgeOutbox& out) {
  if (v.task_id.empty()) {
    return;
  }
  msg::TaskState st = msg::TaskState::Assigned;
  const auto* view = registry_.find(v.entry.robot_id);
  if (!v.failure.empty()) {
    st = msg::TaskState::Failed;
  } else if (v.goal >= v.goals.size()) {
    st = msg::TaskState::Done;
  } else if (view != nullptr && view->state && v.has_order) {
    const auto& g = v.goals[v.goal];
    const auto* a = findAction(*view->state, goalActionId(v, v.goal));
    const bool running = a != nullptr && (a->actionStatus == "RUNNING" || a->actionStatus == "INITIALIZING");
    if (g.action == msg::GoalAction::Load) {
      st = running ? msg::TaskState::Loading : msg::TaskState::EnRoute;
    } else if (g.action == msg::GoalAction::Unload) {
      st = running ? msg::TaskState::Unloading : msg::TaskState::Delivering;
    } else {
      st = msg::TaskState::EnRoute;
    }
  }
  if (st == v.reported && v.goal == v.reported_goal) {
    return;
  }
  v.reported = st;
  v.reported_goal = v.goal;
  msg::TaskStatus ts;
  ts.robot_id = v.entry.robot_id;
  ts.task_id = v.task_id;
  ts.revision = v.revision;
  ts.state = st;
  ts.progress = v.goals.empty() ? 1.0F : static_cast<float>(v.goal) / static_cast<float>(v.goals.size());
  ts.error = v.failure.substr(0, 255);
  ts.stamp_ns = nowNs;
  ts.step = static_cast<std::uint32_t>(std::min(v.goal + 1, v.goals.size()));
  out.statuses.push_back(std::move(ts));
}

void BridgeNode::tick(std::int64_t nowNs, BridgeOutbox& out) {
  for (auto& [id, v] : vehicles_) {
    const auto* view = registry_.find(id);
    if (view == nullptr || !view->state) {
      continue;
    }
    const auto& s = *view->state;
    const bool admitted = admit(v, *view, nowNs, out);
    const bool online = view->health == VehicleHealth::kOnline && admitted;
    const bool atBaseEnd = online && s.newBaseRequest.value_or(false);
    if (atBaseEnd && !v.at_base_end && v.release && !v.stale_release && !holdsOrdersBack(v, *view, nowNs)) {
      const auto& base = v.release->base;
      const int at = vda5050::OrderBuilder::roadmapNode(s.lastNodeId);
      const auto it =
          std::find_if(base.begin(), base.end(), [&](const msg::RouteNode& n) { return n.node == at; });
      if (it != base.end() && it + 1 != base.end()) {
        ++counters_.late_updates;
      }
    }
    v.at_base_end = atBaseEnd;
    if (online) {
      watchOrder(v, s, nowNs, out);
      cancelWhenHeld(v, s, nowNs, out);
      trackGoals(v, *view, nowNs, out);
      stopStrayCharging(v, s, nowNs, out);
      followRelease(v, *view, nowNs, out);
      reportTask(v, nowNs, out);
    }
    const bool acting = std::any_of(s.actionStates.begin(), s.actionStates.end(),
                                    [](const auto& a) { return a.actionStatus == "RUNNING"; });
    Pose2 pose;
    if (s.agvPosition) {
      pose = {s.agvPosition->x, s.agvPosition->y, s.agvPosition->theta};
      if (!v.home) {
        v.home = pose;
      }
    }
    if (online) {
      msg::RobotState rs;
      rs.robot_id = id;
      rs.stamp_ns = nowNs;
      rs.pose = pose;
      rs.v = s.velocity ? s.velocity->vx : 0.0;
      rs.w = s.velocity ? s.velocity->omega : 0.0;
      rs.mode = s.batteryState.charging                                          ? msg::RobotMode::Charging
                : acting                                                         ? msg::RobotMode::Loading
                : (s.paused.value_or(false) || s.newBaseRequest.value_or(false)) ? msg::RobotMode::Waiting
                : s.driving                                                      ? msg::RobotMode::Moving
                                                                                 : msg::RobotMode::Idle;
      rs.battery = static_cast<float>(s.batteryState.batteryCharge / 100.0);
      rs.task_id = v.task_id;
      rs.radius = static_cast<float>(vda5050::footprint(*view->factsheet).radius);
      out.states.push_back(std::move(rs));
    }
    msg::TrafficProgress p;
    p.robot_id = id;
    p.epoch = v.release ? v.release->epoch : 0;
    p.node = vda5050::OrderBuilder::roadmapNode(s.lastNodeId);
    p.pose = pose;
    if (!v.task_id.empty() && v.goal < v.goals.size() && v.failure.empty()) {
      p.has_goal = true;
      p.goal = v.goals[v.goal].pose;
      p.goal_station = v.goals[v.goal].station;
      p.priority = v.priority;
    } else if (v.home) {
      p.has_goal = true;
      p.goal = *v.home;
    }
    p.holding = !online || acting || s.paused.value_or(false) || s.batteryState.charging;
    // Reported blocked, a robot is held by the traffic manager, which cuts its release back to its
    // next node and plans the others over the rest. A vehicle stopped by its protective field keeps
    // its order's base and drives on by itself once the field is clear: while it holds more than
    // its next node it is only late (the dependencies cover that) until cancelWhenHeld() ends the
    // order. (Reported at once, a vehicle drove on into nodes the plan had given others: its reports
    // were refused from then on and it stood for good; once two vehicles touched.)
    p.blocked = (s.safetyState.fieldViolation && baseAhead(s) <= 1) || v.gave_up;
    p.follows = online;
    p.stamp_ns = nowNs;
    out.progress.push_back(std::move(p));
  }
}

}  // namespace fleet::vdabridge
