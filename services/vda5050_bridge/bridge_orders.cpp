// The bridge's orders: when one may be sent (admission, backoff after failures, the field's hold),
// how it follows the traffic release, and what happens when the vehicle rejects or ignores it.

#include "bridge_node.hpp"

#include <algorithm>
#include <cstdio>

#include "fleet/vda5050/order_rejection.hpp"
#include "vehicle_state.hpp"

namespace fleet::vdabridge {

using bridge_detail::baseAhead;
using vda5050::VehicleHealth;

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
      if (!g.load_id.empty()) {
        a.actionParameters.push_back({"loadId", g.load_id});  // VDA 5050 pick / drop parameter
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
}  // namespace fleet::vdabridge
