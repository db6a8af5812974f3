#pragma once

// A simulated VDA 5050 vehicle on a unicycle integrated at 10 Hz, the way the simulator moves a
// robot, for the vehicle tests and the schema samples.

#include <algorithm>
#include <cmath>
#include <functional>

#include "fleet/sim/vda5050_vehicle.hpp"

namespace fleet::sim::test {

inline Vda5050VehicleConfig rigConfig() {
  Vda5050VehicleConfig c;
  c.serial = "AGV-1";
  c.mapId = "small";
  return c;
}

struct Rig {
  Vda5050Vehicle vehicle{rigConfig(), Pose2{0.0, 0.0, 0.0}};
  Pose2 pose{0.0, 0.0, 0.0};
  double t = 0.0;
  bool person = false;
  bool warned = false;  ///< a person in the warning field
  double accel = 0.0;   ///< m/s² the speed follows the command with (0: at once, as an ideal unicycle)
  double v = 0.0;

  /// Steps for `seconds`; `after_step` (if any) runs after each step.
  void run(double seconds, const std::function<void()>& after_step = {}) {
    for (int k = 0; k < static_cast<int>(seconds * 10); ++k) {
      const auto c = vehicle.step(t, pose, person, warned);
      v = accel > 0.0 ? std::clamp(c.v, v - accel * 0.1, v + accel * 0.1) : c.v;
      pose.x += v * std::cos(pose.theta) * 0.1;
      pose.y += v * std::sin(pose.theta) * 0.1;
      pose.theta += c.w * 0.1;
      t += 0.1;
      if (after_step) {
        after_step();
      }
    }
  }
  vda5050::State state() { return vehicle.takeState(t, 0); }
};

}  // namespace fleet::sim::test
