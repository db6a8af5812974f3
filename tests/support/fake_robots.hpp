// Robots played by a test over DDS (no agent, no simulator): each publishes its RobotState and
// finishes every task it is assigned at once, reporting each step. Header-only; the tests that
// include it link fleet::transport.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "fleet/core/clock.hpp"
#include "fleet/transport/dds.hpp"

namespace fleet::test {

/// Robots played by the test: publish RobotState, obey TaskAssignment by reporting each step.
struct FakeRobots {
  /// Where the first robot stands; the others 1 m apart in x.
  Vec2 origin{0, 0};
  explicit FakeRobots(transport::Participant& p, int n) : states(p), statuses(p), orders(p) {
    for (int i = 0; i < n; ++i) {
      ids.push_back("r" + std::to_string(i));
    }
    states.forRobots(ids);  // as an agent does at start: its writers match before the first report
    statuses.forRobots(ids);
  }
  void publishStates() {
    WallClock c;
    for (std::size_t i = 0; i < ids.size(); ++i) {
      msg::RobotState s;
      s.robot_id = ids[i];
      s.stamp_ns = c.nowNs();
      s.pose = {origin.x + static_cast<double>(i), origin.y, 0};
      s.battery = 0.9f;
      s.radius = 0.3f;
      s.task_id = current.count(ids[i]) ? current[ids[i]].task_id : "";
      states.write(s);
    }
  }
  /// Takes new orders; finishes every task held (reporting each step).
  void work() {
    for (auto& a : orders.take()) {
      if (a.task_id.empty()) {
        current.erase(a.robot_id);
      } else {
        current[a.robot_id] = a;
        received.push_back(a);
      }
    }
    WallClock c;
    for (auto it = current.begin(); it != current.end();) {
      const auto& a = it->second;
      for (auto st : {msg::TaskState::EnRoute, msg::TaskState::Loading, msg::TaskState::Delivering,
                      msg::TaskState::Unloading, msg::TaskState::Done}) {
        statuses.write({a.robot_id, a.task_id, a.revision, st, 1.0f, "", c.nowNs()});
      }
      it = current.erase(it);
    }
  }
  std::vector<std::string> ids;
  transport::Writer<msg::RobotState> states;
  transport::Writer<msg::TaskStatus> statuses;
  transport::Reader<msg::TaskAssignment> orders;
  std::map<std::string, msg::TaskAssignment> current;
  std::vector<msg::TaskAssignment> received;
};

}  // namespace fleet::test
