// Seed 003 Fig. 4.2: the pose controller closes the loop on the EKF estimate, not on raw odometry.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "fleet/control/diff_drive_base.hpp"
#include "fleet/control/lyapunov_pose_controller.hpp"
#include "fleet/control/velocity_limits.hpp"
#include "fleet/estimation/pose_ekf.hpp"
#include "square_drive_sim.hpp"

using namespace fleet;
using namespace fleet::estimation;

namespace {

struct Outcome {
  Pose2 truth;
  Pose2 estimate;
};

/// Robot with noisy encoders (eq. 3.9), compass and wall lines, driven by the two-region controller
/// under the speed/acceleration limits to the Sim 2 goals.
Outcome driveTo(const Pose2& goal, bool use_ekf_corrections, unsigned seed) {
  const sim::SensorSetup s;
  auto base = control::DiffDriveBase::create(s.wheelBase, control::VelocityLimits{}, Pose2{}).value();
  PoseEkf ekf = PoseEkf::create(EkfParams{}, Pose2{}, Eigen::Matrix3d::Identity() * 1e-6).value();
  control::LyapunovPoseController ctl;
  const std::vector<MapLine> map = sim::roomMap();
  std::mt19937 rng(seed);
  std::normal_distribution<double> n01(0.0, 1.0);
  for (int k = 1; k <= 600; ++k) {
    auto cmd = ctl.step(ekf.pose(), goal);
    EXPECT_TRUE(cmd.has_value());
    const auto r = base.step(cmd->cmd, 0.1);
    ekf.predict(r.ds_left + std::sqrt(s.delta * std::abs(r.ds_left)) * n01(rng),
                r.ds_right + std::sqrt(s.delta * std::abs(r.ds_right)) * n01(rng));
    if (!use_ekf_corrections) {
      continue;
    }
    ekf.updateCompass(wrapAngle(base.pose().theta + std::sqrt(s.compass_var) * n01(rng)));
    if (k % s.laser_every == 0) {
      std::vector<LineObservation> lines;
      for (const MapLine& line : map) {
        const LinePrediction p = predictLine(base.pose(), line);
        if (std::cos(p.psi) > -0.1) {
          lines.push_back({p.r + std::sqrt(s.line_var_r) * n01(rng),
                           wrapAngle(p.psi + std::sqrt(s.line_var_psi) * n01(rng)), s.line_var_r,
                           s.line_var_psi});
        }
      }
      ekf.updateLines(map, lines);
    }
  }
  return {base.pose(), ekf.pose()};
}

}  // namespace

TEST(ClosedLoop, ControllerOnEkfEstimateReachesSim2Goals) {
  double fused_error = 0.0;
  double odometry_error = 0.0;
  for (const double deg : {30.0, 60.0, 90.0}) {
    const Pose2 goal{2.0, 2.0, deg2rad(deg)};
    for (unsigned seed = 1; seed <= 3; ++seed) {
      const Outcome o = driveTo(goal, true, seed);
      fused_error += distance(o.truth, goal);
      odometry_error += distance(driveTo(goal, false, seed).truth, goal);
      EXPECT_LT(distance(o.truth, goal), 0.05) << deg << " seed " << seed;
      EXPECT_LT(std::abs(angleDiff(o.truth.theta, goal.theta)), deg2rad(2.0)) << deg << " seed " << seed;
      EXPECT_LT(distance(o.truth, o.estimate), 0.03);
    }
  }
  std::printf("mean final position error: fused %.4f m, odometry only %.4f m\n", fused_error / 9,
              odometry_error / 9);
  EXPECT_LT(fused_error, odometry_error);  // the estimate, not the controller, limits the accuracy
}
