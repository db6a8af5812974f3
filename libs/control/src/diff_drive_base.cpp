#include "fleet/control/diff_drive_base.hpp"

#include <cmath>

namespace fleet::control {

Expected<DiffDriveBase> DiffDriveBase::create(double wheelBase, const VelocityLimits& limits,
                                              const Pose2& start) {
  auto kin = DiffDriveKinematics::create(wheelBase);
  if (!kin) {
    return fleet::unexpected(kin.error());
  }
  if (auto ok = limits.validate(); !ok) {
    return fleet::unexpected(ok.error());
  }
  if (!start.isFinite()) {
    return fleet::unexpected("non_finite_pose", "start pose is NaN/inf");
  }
  return DiffDriveBase(*kin, limits, start);
}

DiffDriveBase::StepResult DiffDriveBase::step(Twist request, double dt) {
  StepResult r;
  r.applied = applyLimits(limits_, request, twist_, dt);
  if (!std::isfinite(dt) || dt <= 0.0) {
    return r;
  }
  twist_ = r.applied.twist;
  pose_ = DiffDriveKinematics::integrateExact(pose_, twist_, dt);
  const WheelSpeeds w = kin_.toWheelSpeeds(twist_);
  r.ds_left = w.left * dt;
  r.ds_right = w.right * dt;
  return r;
}

}  // namespace fleet::control
