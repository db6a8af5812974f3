// A task's goals at the vehicle, passed in turn (a load or unload action finished, or the release
// ended at the goal), a charge goal's charging started, watched and ended, and stray charging
// stopped.

#include "bridge_node.hpp"

#include <cmath>

#include "vehicle_state.hpp"

namespace fleet::vdabridge {

using bridge_detail::findAction;

namespace {

/// A release's last node this close to a goal's pose is the goal's node (station nodes lie on the
/// station's pose; the traffic manager puts a goal at most this far from its node).
constexpr double kGoalReach = 0.5;  // m
}  // namespace

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
      } else if (g.duration_s > 0) {
        // A wait (or a goal that dwells without an action): the vehicle stands there that long.
        if (v.dwell_since_ns < 0) {
          v.dwell_since_ns = nowNs;
        }
        if (static_cast<double>(nowNs - v.dwell_since_ns) * 1e-9 < g.duration_s) {
          return;
        }
        v.dwell_since_ns = -1;
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
}  // namespace fleet::vdabridge
