#pragma once

#include "fleet/control/diff_drive_kinematics.hpp"
#include "fleet/control/twist.hpp"
#include "fleet/control/velocity_limits.hpp"
#include "fleet/core/expected.hpp"
#include "fleet/core/pose2.hpp"

namespace fleet::control {

/// A simulated (or commanded) differential-drive base: each step limits the requested twist to the
/// speed and acceleration bounds, moves the pose along the exact arc, and reports the wheel
/// increments an encoder would have measured (noise is the simulator's business).
class DiffDriveBase {
 public:
  static Expected<DiffDriveBase> create(double wheelBase, const VelocityLimits& limits, const Pose2& start);

  struct StepResult {
    LimitedTwist applied;  ///< what was executed (flags: NaN request rejected, bounds hit)
    double ds_left = 0.0;  ///< wheel increments of this step [m]
    double ds_right = 0.0;
  };
  StepResult step(Twist request, double dt);

  [[nodiscard]] const Pose2& pose() const { return pose_; }
  [[nodiscard]] const Twist& twist() const { return twist_; }
  [[nodiscard]] const DiffDriveKinematics& kinematics() const { return kin_; }
  void teleport(const Pose2& pose) {
    pose_ = pose;
    twist_ = {};
  }

 private:
  DiffDriveBase(DiffDriveKinematics kin, const VelocityLimits& limits, const Pose2& start)
      : kin_(kin), limits_(limits), pose_(start) {}
  DiffDriveKinematics kin_;
  VelocityLimits limits_;
  Pose2 pose_;
  Twist twist_;
};

}  // namespace fleet::control
