#pragma once

// The bridge and one simulated VDA 5050 vehicle in a loop, for the bridge's tests: the vehicle
// stepped at 10 Hz, the bridge cycling after each step, orders and instant actions carried over.

#include <gtest/gtest.h>

#include <algorithm>
#include <optional>
#include <string>
#include <vector>

#include "bridge_node.hpp"
#include "fleet/vda5050/instant_actions.hpp"
#include "vehicle_rig.hpp"

namespace fleet::vdabridge::bridge_test {

inline const std::string kTopic = "uagv/v2/fleet-sim/AGV-1/";

inline BridgeSettings settings() {
  return {"uagv", "small", {{"fleet-sim", "AGV-1", "r1"}}, 0.2};
}

/// Roadmap nodes 0..9 at (k, 0), joined both ways.
inline msg::Roadmap lineRoadmap() {
  msg::Roadmap m;
  for (int k = 0; k < 10; ++k) {
    m.nodes.push_back({k, static_cast<double>(k), 0.0});
    if (k > 0) {
      m.edges.push_back({k - 1, k, 1.0F, true});
      m.edges.push_back({k, k - 1, 1.0F, true});
    }
  }
  return m;
}

inline msg::TrafficRelease release(std::vector<int> base, std::vector<int> horizon = {}) {
  msg::TrafficRelease r;
  r.robot_id = "r1";
  r.epoch = 1;
  for (int k : base) {
    r.base.push_back({k, static_cast<double>(k), 0.0});
  }
  for (int k : horizon) {
    r.horizon.push_back({k, static_cast<double>(k), 0.0});
  }
  return r;
}

/// The bridge and one simulated vehicle, the vehicle stepped at 10 Hz and the bridge cycling after
/// each step with the vehicle's latest state, its orders and instant actions carried to the vehicle.
struct Loop {
  BridgeNode bridge;
  sim::test::Rig rig;  // "fleet-sim"/"AGV-1" on map "small", at (0, 0) facing +x
  std::int64_t now = 0;
  bool deliver = true;          // false: orders are lost on the way
  bool deliverInstants = true;  // false: instant actions are lost on the way
  std::vector<vda5050::Order> orders;
  std::vector<std::string> instants;
  std::vector<std::string> warnings;
  msg::TrafficProgress progress;
  std::vector<msg::TaskStatus> statuses;
  std::optional<msg::RobotState> robot;  // the latest RobotState

  explicit Loop(BridgeSettings s = settings(), bool factsheet = true) : bridge(std::move(s)) {
    bridge.onRoadmap(lineRoadmap());
    if (factsheet) {
      sendFactsheet();
    }
    cycle();
  }
  void sendFactsheet() {
    BridgeOutbox out;
    bridge.onMqtt(kTopic + "factsheet", vda5050::toJson(rig.vehicle.factsheet(0)).dump(), out);
  }

  void cycle() {
    BridgeOutbox out;
    bridge.onMqtt(kTopic + "state", vda5050::toJson(rig.vehicle.takeState(rig.t, now)).dump(), out);
    bridge.tick(now, out);
    for (const auto& m : out.mqtt) {
      if (m.topic == kTopic + "order") {
        auto o = vda5050::parseOrder(m.payload);
        ASSERT_TRUE(o) << o.error().message;
        orders.push_back(*o);
        if (deliver) {
          (void)rig.vehicle.onOrder(*o);
        }
      } else if (m.topic == kTopic + "instantActions") {
        auto ia = vda5050::parseInstantActions(m.payload);
        ASSERT_TRUE(ia) << ia.error().message;
        for (const auto& a : ia->actions) {
          instants.push_back(a.actionType);
        }
        if (deliverInstants) {
          rig.vehicle.onInstantActions(*ia);
        }
      }
    }
    warnings.insert(warnings.end(), out.warnings.begin(), out.warnings.end());
    warnings.insert(warnings.end(), out.notices.begin(), out.notices.end());
    if (!out.progress.empty()) {
      progress = out.progress.back();
    }
    statuses.insert(statuses.end(), out.statuses.begin(), out.statuses.end());
    if (!out.states.empty()) {
      robot = out.states.back();
    }
  }
  void run(double seconds) {
    for (int k = 0; k < static_cast<int>(seconds * 10 + 0.5); ++k) {
      rig.run(0.1);
      now = static_cast<std::int64_t>(rig.t * 1e9);
      cycle();
    }
  }
  /// Runs until the vehicle's last node is `node` (at most `seconds`).
  bool runUntilAt(const std::string& node, double seconds) {
    for (int k = 0; k < static_cast<int>(seconds * 10); ++k) {
      if (rig.vehicle.lastNodeId() == node) {
        return true;
      }
      run(0.1);
    }
    return rig.vehicle.lastNodeId() == node;
  }
  void assign(const std::string& task, double goal_x) {
    msg::TaskAssignment a;
    a.robot_id = "r1";
    a.task_id = task;
    a.goals = {{{goal_x, 0.0, 0.0}, "", msg::GoalAction::None, 0.0}};
    BridgeOutbox out;
    bridge.onAssignment(a, now, out);
  }
  /// Task `task`, driven by a first order n0, n1 to stand at n1 with it done.
  void standAtN1(const std::string& task, double goal_x) {
    assign(task, goal_x);
    bridge.onRelease(release({0, 1}));
    run(0.1);
    ASSERT_TRUE(runUntilAt("n1", 20.0));
    run(1.0);
  }
  [[nodiscard]] bool warned(const std::string& part) const {
    return std::any_of(warnings.begin(), warnings.end(),
                       [&](const std::string& w) { return w.find(part) != std::string::npos; });
  }
  vda5050::State state() { return rig.vehicle.takeState(rig.t, now); }
};

}  // namespace fleet::vdabridge::bridge_test
