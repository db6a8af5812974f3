#include "bridge_node.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "fleet/vda5050/header.hpp"
#include "fleet/vda5050/instant_actions.hpp"
#include "fleet/vda5050/order_rejection.hpp"

namespace fleet::vdabridge {

using vda5050::VehicleHealth;

namespace {

/// A release's last node this close to a goal's pose is the goal's node (station nodes lie on the
/// station's pose; the traffic manager puts a goal at most this far from its node).
constexpr double kGoalReach = 0.5;  // m

const vda5050::ActionState* findAction(const vda5050::State& s, const std::string& id) {
  for (const auto& a : s.actionStates) {
    if (a.actionId == id) {
      return &a;
    }
  }
  return nullptr;
}

}  // namespace

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
    v.failure.clear();
    freshChance(v);
    v.reported = msg::TaskState::Queued;
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

void BridgeNode::freshChance(Vehicle& v) {
  // Something changed that may let an order through: what the vehicle refused before does not count.
  if (v.gave_up) {
    v.gave_up = false;
    v.failures = 0;
    v.retry_ns = 0;
  }
}

void BridgeNode::orderFailed(Vehicle& v, const std::string& why, std::int64_t nowNs, BridgeOutbox& out) {
  ++v.failures;
  if (v.failures > settings_.order_retries) {
    v.gave_up = true;
    ++counters_.gave_up;
    out.warnings.push_back(v.entry.robot_id + ": no order taken after " + std::to_string(v.failures) +
                           " attempts (last: " + why +
                           "); reported blocked to the traffic manager until its release or task changes");
    return;
  }
  const double wait = settings_.retry_backoff_s * static_cast<double>(1 << std::min(v.failures - 1, 20));
  v.retry_ns = nowNs + static_cast<std::int64_t>(wait * 1e9);
}

void BridgeNode::watchOrder(Vehicle& v, const vda5050::State& s, std::int64_t nowNs, BridgeOutbox& out) {
  if (!v.has_order) {
    v.awaiting = false;  // cancelled: what was in flight does not matter any more
  }
  if (!v.awaiting) {
    return;
  }
  const auto& id = v.builder.orderId();
  if (s.orderId == id && s.orderUpdateId >= v.sent_update) {
    v.awaiting = false;
    v.failures = 0;
    return;
  }
  std::string why;
  if (const auto r = vda5050::findOrderRejection(s, id, v.sent_update)) {
    why = r->errorType + ": " + r->description;
  } else if (static_cast<double>(nowNs - v.sent_ns) * 1e-9 > settings_.order_ack_timeout_s) {
    why = "neither taken nor rejected in " + std::to_string(static_cast<int>(settings_.order_ack_timeout_s)) +
          " s";
  } else {
    return;
  }
  v.awaiting = false;
  ++counters_.rejected;
  const bool update = s.orderId == id && v.builder.rollbackTo(s.orderUpdateId);
  out.warnings.push_back(
      v.entry.robot_id + ": order " + id + " update " + std::to_string(v.sent_update) + " rejected (" + why +
      "); " +
      (update ? "the next update starts at the base end of update " + std::to_string(s.orderUpdateId)
              : std::string("a new order starts from its latest state")));
  if (!update) {
    v.has_order = false;  // the next order is a new one, built from where the vehicle then is
  }
  orderFailed(v, why, nowNs, out);
}

namespace {
/// Base nodes the vehicle still holds ahead of its last node.
std::size_t baseAhead(const vda5050::State& s) {
  return static_cast<std::size_t>(std::count_if(s.nodeStates.begin(), s.nodeStates.end(),
                                                [](const vda5050::NodeState& n) { return n.released; }));
}
}  // namespace

void BridgeNode::cancelWhenHeld(Vehicle& v, const vda5050::State& s, std::int64_t nowNs, BridgeOutbox& out) {
  if (!s.safetyState.fieldViolation) {
    v.field_since_ns = -1;
    v.field_cancelled = false;
    return;
  }
  if (v.field_since_ns < 0) {
    v.field_since_ns = nowNs;
  }
  if (static_cast<double>(nowNs - v.field_since_ns) * 1e-9 < settings_.field_cancel_s || baseAhead(s) <= 1 ||
      !v.has_order || v.cancel_sent) {
    return;
  }
  // The base cannot be shortened by an update (VDA 5050 2.1, 6.6): it ends only with the order.
  instant(v, "cancelOrder", nowNs, out);
  ++counters_.cancels;
  ++counters_.field_cancels;
  v.cancel_sent = true;
  v.has_order = false;  // the next order starts from where the vehicle then stands
  v.field_cancelled = true;
  if (v.release) {
    v.stale_release = std::pair{v.release->epoch, v.release->seq};
  }
}

void BridgeNode::trackGoals(Vehicle& v, const vda5050::VehicleView& view, std::int64_t nowNs,
                            BridgeOutbox& out) {
  while (!v.task_id.empty() && v.goal < v.goals.size() && v.failure.empty()) {
    const auto& g = v.goals[v.goal];
    if (g.action == msg::GoalAction::Load || g.action == msg::GoalAction::Unload) {
      const auto* a = findAction(*view.state, goalActionId(v, v.goal));
      if (a == nullptr || a->actionStatus != "FINISHED") {
        return;
      }
    } else {
      // The release must end at this goal, not at the last task's (a release that has not caught
      // up with a new task still ends where the vehicle stands: a charge task began with a
      // startCharging at the drop-off it came from).
      const bool there =
          v.release && v.release->ends_at_goal && !v.release->base.empty() &&
          std::hypot(v.release->base.back().x - g.pose.x, v.release->base.back().y - g.pose.y) <=
              kGoalReach &&
          view.state->nodeStates.empty() &&
          vda5050::OrderBuilder::roadmapNode(view.state->lastNodeId) == v.release->base.back().node;
      if (!there) {
        return;
      }
      if (g.action == msg::GoalAction::Charge) {
        if (!charged(v, *view.state, nowNs, out)) {
          return;
        }
        v.charge_arrived_ns = -1;
        v.charge_attempts = 0;
      }
    }
    ++v.goal;
  }
}

bool BridgeNode::charged(Vehicle& v, const vda5050::State& s, std::int64_t nowNs, BridgeOutbox& out) {
  constexpr double kAnswerS = 5.0;  // a startCharging without charging by then is sent again
  constexpr int kAttempts = 3;      // startCharging sent at most this often at one goal
  if (v.charge_arrived_ns < 0) {
    v.charge_arrived_ns = nowNs;
  }
  const auto since = [&](std::int64_t t) { return static_cast<double>(nowNs - t) * 1e-9; };
  // The fleet manager ends the task once the battery is charged; a charger that does not charge
  // (or a vehicle that does not start) holds it no longer than the goal's duration
  // (charge_max_s) from its arrival, as for a robot agent.
  if (since(v.charge_arrived_ns) >= v.goals[v.goal].duration_s) {
    if (s.batteryState.charging) {
      instant(v, "stopCharging", nowNs, out);
      ++counters_.charge_stops;
      v.charge_stop_ns = nowNs;
    }
    v.charge_action.clear();
    return true;
  }
  if (s.batteryState.charging) {
    return false;
  }
  const auto* a = v.charge_action.empty() ? nullptr : findAction(s, v.charge_action);
  const bool failed = a != nullptr && a->actionStatus == "FAILED";
  const bool unanswered = !v.charge_action.empty() && !failed && since(v.charge_sent_ns) >= kAnswerS;
  if (!v.charge_action.empty() && !failed && !unanswered) {
    return false;  // sent, not answered yet
  }
  if (failed) {
    ++counters_.charge_failures;
  }
  if (v.charge_attempts >= kAttempts) {
    v.failure = failed ? "startCharging failed: " + a->resultDescription.value_or("no reason given")
                       : "startCharging " + std::to_string(kAttempts) + " times, the vehicle never charged";
    out.warnings.push_back(v.entry.robot_id + ": " + v.failure + " (task " + v.task_id + " failed)");
    return false;
  }
  if (s.driving) {
    return false;  // still settling on the node: a vehicle on the move does not start charging
  }
  // A fresh id each time: the vehicle's state may still list the last attempt's FAILED.
  v.charge_action = goalActionId(v, v.goal) + "-c" + std::to_string(++v.charge_attempts);
  v.charge_sent_ns = nowNs;
  instant(v, "startCharging", nowNs, out, v.charge_action);
  ++counters_.charges;
  return false;
}

void BridgeNode::stopStrayCharging(Vehicle& v, const vda5050::State& s, std::int64_t nowNs,
                                   BridgeOutbox& out) {
  const bool wanted = !v.charge_action.empty() && v.failure.empty() && !v.task_id.empty() &&
                      v.goal < v.goals.size() && v.goals[v.goal].action == msg::GoalAction::Charge;
  if (!s.batteryState.charging || wanted) {
    v.stray_stops = 0;
    return;
  }
  // Again after a while: a stopCharging lost on the way (QoS 0) must not hold the vehicle for ever.
  constexpr double kResendS = 5.0;
  if (v.charge_stop_ns >= 0 && static_cast<double>(nowNs - v.charge_stop_ns) * 1e-9 < kResendS) {
    return;
  }
  instant(v, "stopCharging", nowNs, out);
  ++counters_.charge_stops;
  v.charge_stop_ns = nowNs;
  if (++v.stray_stops == 3) {
    out.warnings.push_back(v.entry.robot_id +
                           ": still charging after 3 stopCharging; no order goes to it while it charges "
                           "(it is reported holding, so traffic is planned round it)");
  }
}

bool BridgeNode::holdsOrdersBack(const Vehicle& v, const vda5050::VehicleView& view,
                                 std::int64_t nowNs) const {
  // Held where it stands (the traffic manager plans round it): an order now would be the release
  // it had, cancelled again; the next comes once its field is clear, from the release then.
  // Charging, it takes no order (stopCharging first: stopStrayCharging()).
  return v.gave_up || nowNs < v.retry_ns || v.field_cancelled || view.state->batteryState.charging;
}

void BridgeNode::followRelease(Vehicle& v, const vda5050::VehicleView& view, std::int64_t nowNs,
                               BridgeOutbox& out) {
  if (!v.release || v.release->base.empty() || view.health != VehicleHealth::kOnline ||
      holdsOrdersBack(v, view, nowNs)) {
    return;
  }
  const auto& r = *v.release;
  if (v.stale_release && *v.stale_release != std::pair{r.epoch, r.seq}) {
    v.stale_release.reset();
  }
  // What a held robot keeps of its release: the node it reported last and the next one.
  const std::size_t keep = v.stale_release ? std::min<std::size_t>(2, r.base.size()) : r.base.size();
  vda5050::ReleaseInput in;
  for (std::size_t i = 0; i < keep; ++i) {
    in.base.push_back({r.base[i].node, r.base[i].x, r.base[i].y});
  }
  const bool whole = keep == r.base.size();
  if (whole) {
    for (const auto& n : r.horizon) {
      in.horizon.push_back({n.node, n.x, n.y});
    }
  }
  if (whole && r.ends_at_goal && !v.task_id.empty() && v.goal < v.goals.size()) {
    const auto& g = v.goals[v.goal];
    if (g.action == msg::GoalAction::Load || g.action == msg::GoalAction::Unload) {
      vda5050::Action a{
          g.action == msg::GoalAction::Load ? "pick" : "drop", goalActionId(v, v.goal), "HARD", {}, {}};
      if (!g.station.empty()) {
        a.actionParameters.push_back({"stationId", g.station});
      }
      a.actionParameters.push_back({"duration", g.duration_s});
      in.actions.emplace_back(r.base.back().node, std::move(a));
    }
  }
  const auto& s = *view.state;
  if (!v.has_order) {
    if (!s.nodeStates.empty()) {
      if (!v.cancel_sent) {  // an order of someone else's (a previous bridge): end it first
        instant(v, "cancelOrder", nowNs, out);
        ++counters_.cancels;
        v.cancel_sent = true;
      }
      return;
    }
    // A new order starts where the vehicle stands, or the vehicle rejects it (noRouteError).
    auto from = vda5050::startAtVehicle(in, s.lastNodeId, roadmap_);
    if (!from) {
      out.warnings.push_back(v.entry.robot_id + ": no new order: " + from.error().message);
      orderFailed(v, from.error().message, nowNs, out);
      return;
    }
    in = std::move(*from);
    if (in.base.size() < 2 && in.actions.empty()) {
      return;  // holding on the node it stands on: nothing to drive
    }
    const std::string id =
        (v.task_id.empty() ? v.entry.robot_id : v.task_id) + "-" + std::to_string(++v.orders_started);
    auto o = v.builder.start(id, in, nowNs);
    if (!o) {
      out.warnings.push_back(v.entry.robot_id + ": " + o.error().message);
      return;
    }
    v.has_order = true;
    v.cancel_sent = false;
    sendOrder(v, *o, nowNs, out);
    return;
  }
  if (s.orderId != v.builder.orderId()) {
    return;  // the vehicle has not taken the order yet
  }
  auto up = v.builder.extend(in, s.lastNodeSequenceId, nowNs);
  if (!up && up.error().code == "vda5050.bad_progress") {
    return;  // its state is older than the order it took: wait for the next
  }
  if (!up) {
    ++counters_.cannot_stitch;
    out.warnings.push_back(v.entry.robot_id + ": " + up.error().message);
    if (s.nodeStates.empty()) {
      v.has_order = false;  // finished: the next tick starts a new order from where it stands
    } else if (!v.cancel_sent) {
      instant(v, "cancelOrder", nowNs, out);
      ++counters_.cancels;
      v.cancel_sent = true;
      v.has_order = false;
    }
    return;
  }
  if (up->has_value()) {
    sendOrder(v, **up, nowNs, out);
  }
}

std::string BridgeNode::refusal(const vda5050::VehicleView& view) const {
  if (!view.factsheet) {
    return "no factsheet yet (its footprint decides whether the roadmap fits it)";
  }
  if (!roadmap_radius_) {
    return "no roadmap from the traffic manager yet (its robot radius decides whether the vehicle fits)";
  }
  const auto f = vda5050::footprint(*view.factsheet);
  // A millimetre of slack: a footprint given as the robot's own disc, rounded in JSON, still fits.
  constexpr double kSlack = 1e-3;
  if (*roadmap_radius_ > 0.0 && f.radius > *roadmap_radius_ + kSlack) {
    char why[512];
    std::snprintf(
        why, sizeof why,
        "its footprint (a disc of radius %.3f m about its reference point, from its factsheet's %s) "
        "is larger than the robot the roadmap's conflicts are computed for (radius %.3f m): planned "
        "as that robot it could touch others; a roadmap for it needs a robot radius of at least "
        "%.3f m (the site's robot.radius or the traffic manager's roadmap.radius)",
        f.radius, f.source.c_str(), *roadmap_radius_, f.radius);
    return why;
  }
  return {};
}

bool BridgeNode::admit(Vehicle& v, const vda5050::VehicleView& view, std::int64_t nowNs, BridgeOutbox& out) {
  const std::string why = refusal(view);
  if (why != v.refused) {
    if (why.empty()) {
      const auto f = vda5050::footprint(*view.factsheet);
      char fits[200];
      if (*roadmap_radius_ > 0.0) {
        std::snprintf(fits, sizeof fits,
                      "joins the fleet: its footprint (radius %.3f m, %s) fits the roadmap's robot (%.3f m)",
                      f.radius, f.source.c_str(), *roadmap_radius_);
      } else {
        std::snprintf(fits, sizeof fits,
                      "joins the fleet: its footprint (radius %.3f m, %s) not checked (the roadmap states no "
                      "robot radius)",
                      f.radius, f.source.c_str());
      }
      out.notices.push_back(v.entry.robot_id + ": " + fits);
    } else {
      ++counters_.refused_vehicles;
      out.notices.push_back(v.entry.robot_id + ": not in the fleet: " + why);
    }
    v.refused = why;
  }
  if (!view.factsheet && (v.factsheet_asked_ns < 0 || nowNs - v.factsheet_asked_ns > 30'000'000'000)) {
    instant(v, "factsheetRequest", nowNs, out);
    v.factsheet_asked_ns = nowNs;
  }
  if (!why.empty() && !v.cancel_sent && view.state && !view.state->nodeStates.empty()) {
    instant(v, "cancelOrder", nowNs, out);  // it may not drive a plan made for a smaller robot
    ++counters_.cancels;
    v.cancel_sent = true;
    v.has_order = false;
  }
  return why.empty();
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
  if (st == v.reported) {
    return;
  }
  v.reported = st;
  msg::TaskStatus ts;
  ts.robot_id = v.entry.robot_id;
  ts.task_id = v.task_id;
  ts.revision = v.revision;
  ts.state = st;
  ts.progress = v.goals.empty() ? 1.0F : static_cast<float>(v.goal) / static_cast<float>(v.goals.size());
  ts.error = v.failure.substr(0, 255);
  ts.stamp_ns = nowNs;
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
