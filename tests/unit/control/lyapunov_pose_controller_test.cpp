#include "fleet/control/lyapunov_pose_controller.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "fleet/control/diff_drive_kinematics.hpp"
#include "fleet/core/angles.hpp"

using namespace fleet;
using namespace fleet::control;

namespace {

constexpr double kDt = 0.1;  // seed 003 sim period

/// Seed 003 §5 noise: bounded (uniform) feedback noise on the pose and a relative error on v and ω.
struct Noise {
  double xy = 0.0;
  double theta = 0.0;
  double input = 0.0;
};
const Noise kThesisNoise{0.1, 0.0036, 0.05};

struct SimRun {
  std::vector<Pose2> poses;  // true pose after each step
  std::vector<PoseControlOutput> outputs;
};

SimRun simulate(LyapunovParams p, const Pose2& start, const Pose2& goal, int steps, Noise noise,
                unsigned seed) {
  LyapunovPoseController ctl(p);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  SimRun run;
  Pose2 truth = start;
  for (int k = 0; k < steps; ++k) {
    const Pose2 est{truth.x + noise.xy * u(rng), truth.y + noise.xy * u(rng),
                    wrapAngle(truth.theta + noise.theta * u(rng))};
    auto out = ctl.step(est, goal);
    EXPECT_TRUE(out.has_value());
    Twist cmd = out->cmd;
    cmd.v *= 1.0 + noise.input * u(rng);
    cmd.omega *= 1.0 + noise.input * u(rng);
    truth = DiffDriveKinematics::integrateExact(truth, cmd, kDt);
    run.poses.push_back(truth);
    run.outputs.push_back(*out);
  }
  return run;
}

LyapunovParams withLaw(PoseLaw law) {
  LyapunovParams p;
  p.law = law;
  return p;
}

const Pose2 kSim1Start{-2.0, 3.5, deg2rad(-60.0)};
const Pose2 kOrigin{0.0, 0.0, 0.0};

}  // namespace

TEST(PolarError, MatchesDefinition) {
  // Sim 1 start: the goal bears −60.26°, just right of the −60° heading.
  const PolarError e = polarError(kSim1Start, kOrigin);
  EXPECT_NEAR(e.rho, std::hypot(2.0, 3.5), 1e-12);
  const double bearing = std::atan2(-3.5, 2.0);
  EXPECT_NEAR(e.alpha, bearing - deg2rad(-60.0), 1e-12);
  EXPECT_NEAR(e.phi, bearing, 1e-12);
  // α = φ + θg − θ (eq. 4.6) for random poses, up to wrapping.
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-5.0, 5.0);
  for (int i = 0; i < 1000; ++i) {
    const Pose2 p{u(rng), u(rng), wrapAngle(u(rng))};
    const Pose2 g{u(rng), u(rng), wrapAngle(u(rng))};
    const PolarError q = polarError(p, g);
    EXPECT_NEAR(angleDiff(q.alpha, q.phi + g.theta - p.theta), 0.0, 1e-9);
    EXPECT_GT(q.alpha, -kPi);
    EXPECT_LE(q.alpha, kPi);
  }
}

TEST(GlobalLaw, LyapunovDerivativeIsNegativeSemidefinite) {
  // Analytic V̇_G = ρρ̇ + αα̇ + hφφ̇ with the error dynamics 4.7 must equal −kV ρ² cos²α − k_α α².
  const LyapunovGains g;
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> ur(0.01, 5.0);
  std::uniform_real_distribution<double> ua(-0.5 * kPi + 1e-3, 0.5 * kPi - 1e-3);
  std::uniform_real_distribution<double> uphi(-kPi, kPi);
  for (int i = 0; i < 1000; ++i) {
    const PolarError e{ur(rng), ua(rng), uphi(rng)};
    const Twist t = globalLaw(e, g);
    const double rho_dot = -t.v * std::cos(e.alpha);
    const double phi_dot = t.v * std::sin(e.alpha) / e.rho;
    const double alpha_dot = -t.omega + t.v * std::sin(e.alpha) / e.rho;
    const double vdot = e.rho * rho_dot + e.alpha * alpha_dot + g.h * e.phi * phi_dot;
    const double expected =
        -g.kV * e.rho * e.rho * std::pow(std::cos(e.alpha), 2) - g.kAlpha * e.alpha * e.alpha;
    EXPECT_NEAR(vdot, expected, 1e-9 * (1.0 + std::abs(expected)));
    EXPECT_LE(vdot, 1e-12);
  }
}

TEST(GlobalLaw, LyapunovNonIncreasingAlongDiscreteTrajectory) {
  // Seed 003 behaviour 9: V_G non-increasing along noise-free Δt = 0.1 s trajectories (small tolerance
  // for the discretisation: 1 % of V per step), from many starts where the goal lies ahead.
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-4.0, 4.0);
  std::uniform_real_distribution<double> ua(-1.2, 1.2);
  const LyapunovGains g;
  for (int trial = 0; trial < 50; ++trial) {
    const Pose2 goal{u(rng), u(rng), wrapAngle(u(rng))};
    Pose2 pose{u(rng), u(rng), 0.0};
    pose.theta = wrapAngle(std::atan2(goal.y - pose.y, goal.x - pose.x) - ua(rng));
    double v_prev = lyapunovGlobal(polarError(pose, goal), g.h);
    for (int k = 0; k < 200; ++k) {
      const PolarError e = polarError(pose, goal);
      if (e.rho < 1e-3) {
        break;
      }
      pose = DiffDriveKinematics::integrateExact(pose, globalLaw(e, g), 0.1);
      const double v = lyapunovGlobal(polarError(pose, goal), g.h);
      EXPECT_LE(v, v_prev + 1e-2 * v_prev + 1e-6) << "trial " << trial << " step " << k;
      v_prev = v;
    }
  }
}

TEST(LyapunovPoseController, Sim1NoiseFreeBothLawsConverge) {
  // Seed 003 Sim 1: (−2, 3.5, −60°) → (0, 0, 0°), kV = 1, k_α = 2, k_θ = 1, h = 5, Δt = 0.1 s, 150 samples.
  for (const PoseLaw law : {PoseLaw::kSingleLaw, PoseLaw::kTwoRegion}) {
    const SimRun run = simulate(withLaw(law), kSim1Start, kOrigin, 150, Noise{}, 1);
    const Pose2 end = run.poses.back();
    EXPECT_LT(std::hypot(end.x, end.y), 0.01) << static_cast<int>(law);
    EXPECT_LT(std::abs(end.theta), deg2rad(0.5)) << static_cast<int>(law);
  }
  // The two-region run switches to Ω_L and stays there (thesis: ends at 0.0086, 0.0035, −0.0031).
  const SimRun two = simulate(withLaw(PoseLaw::kTwoRegion), kSim1Start, kOrigin, 150, Noise{}, 1);
  EXPECT_EQ(two.outputs.front().region, ControlRegion::kGlobal);
  EXPECT_EQ(two.outputs.back().region, ControlRegion::kLocal);
  EXPECT_FALSE(two.outputs.front().reverse);  // the goal is ahead at the start
}

TEST(LyapunovPoseController, Sim1WithThesisNoiseOnlyTwoRegionLawSettles) {
  // Thesis noise: feedback ±0.1 m, ±0.0036 rad; ±5 % on v and ω; fixed seeds. Over the last 20 s of a
  // 60 s run the single law's heading keeps swinging (Fig. 4.3a) while the two-region law holds the
  // heading within 0.5° and the position within a few centimetres (Fig. 4.3b).
  constexpr int kSteps = 600;
  constexpr int kTail = 200;
  for (unsigned seed = 1; seed <= 10; ++seed) {
    const SimRun single =
        simulate(withLaw(PoseLaw::kSingleLaw), kSim1Start, kOrigin, kSteps, kThesisNoise, seed);
    const SimRun two =
        simulate(withLaw(PoseLaw::kTwoRegion), kSim1Start, kOrigin, kSteps, kThesisNoise, seed);
    double single_max_th = 0.0;
    double single_max_rho = 0.0;
    double two_max_th = 0.0;
    double two_max_rho = 0.0;
    int single_sign_changes = 0;
    for (int k = kSteps - kTail; k < kSteps; ++k) {
      const auto i = static_cast<std::size_t>(k);
      single_max_th = std::max(single_max_th, std::abs(single.poses[i].theta));
      single_max_rho = std::max(single_max_rho, std::hypot(single.poses[i].x, single.poses[i].y));
      two_max_th = std::max(two_max_th, std::abs(two.poses[i].theta));
      two_max_rho = std::max(two_max_rho, std::hypot(two.poses[i].x, two.poses[i].y));
      if (single.poses[i].theta * single.poses[i - 1].theta < 0.0) {
        ++single_sign_changes;
      }
      EXPECT_EQ(two.outputs[i].region, ControlRegion::kLocal) << "seed " << seed << " step " << k;
    }
    EXPECT_GT(single_max_th, deg2rad(20.0)) << "seed " << seed;
    EXPECT_GT(single_sign_changes, 5) << "seed " << seed;
    EXPECT_LT(single_max_rho, 0.1) << "seed " << seed;  // the position is still reached
    EXPECT_LT(two_max_th, deg2rad(0.5)) << "seed " << seed;
    EXPECT_LT(two_max_rho, 0.08) << "seed " << seed;
  }
}

TEST(LyapunovPoseController, Sim2GoalsWithHeading) {
  // Seed 003 Sim 2: from (0, 0, 0) to (2, 2) with final headings 30°, 60°, 90°.
  for (const double deg : {30.0, 60.0, 90.0}) {
    const Pose2 goal{2.0, 2.0, deg2rad(deg)};
    const SimRun run = simulate(withLaw(PoseLaw::kTwoRegion), kOrigin, goal, 300, Noise{}, 1);
    const Pose2 end = run.poses.back();
    EXPECT_LT(distance(end, goal), 0.01) << deg;
    EXPECT_LT(std::abs(angleDiff(end.theta, goal.theta)), deg2rad(0.5)) << deg;
  }
}

TEST(LyapunovPoseController, DrivesBackwardsWhenGoalIsBehind) {
  const Pose2 start{2.0, 0.3, 0.0};  // goal behind: α ≈ π
  LyapunovParams p;
  LyapunovPoseController ctl(p);
  auto first = ctl.step(start, kOrigin);
  ASSERT_TRUE(first.has_value());
  EXPECT_TRUE(first->reverse);
  EXPECT_LT(first->cmd.v, 0.0);
  const SimRun run = simulate(p, start, kOrigin, 300, Noise{}, 1);
  double max_turn = 0.0;
  for (const Pose2& q : run.poses) {
    max_turn = std::max(max_turn, std::abs(q.theta));
  }
  EXPECT_LT(max_turn, kPi / 2);  // it never turned around
  EXPECT_LT(std::hypot(run.poses.back().x, run.poses.back().y), 0.01);
  EXPECT_LT(std::abs(run.poses.back().theta), deg2rad(0.5));

  p.allowReverse = false;
  LyapunovPoseController fwd(p);
  auto f = fwd.step(start, kOrigin);
  ASSERT_TRUE(f.has_value());
  EXPECT_FALSE(f->reverse);
  EXPECT_GT(std::abs(f->cmd.omega), 0.5);  // turns around instead
}

TEST(LyapunovPoseController, LocalRegionUsesHeadingLaw) {
  LyapunovParams p;
  LyapunovPoseController ctl(p);
  const Pose2 goal{1.0, 1.0, 0.5};
  const Pose2 est{1.05, 1.0, 0.6};  // goal 5 cm behind, heading 0.1 rad too far left
  auto out = ctl.step(est, goal);
  ASSERT_TRUE(out.has_value());
  EXPECT_EQ(out->region, ControlRegion::kLocal);
  EXPECT_NEAR(out->cmd.omega, -p.gains.kTheta * 0.1, 1e-12);
  EXPECT_NEAR(out->cmd.v, p.gains.kV * 0.05 * std::cos(kPi - 0.6), 1e-12);
  EXPECT_LT(out->cmd.v, 0.0);  // backs up toward the goal
  // The single law ignores the region.
  LyapunovParams s = p;
  s.law = PoseLaw::kSingleLaw;
  LyapunovPoseController single(s);
  EXPECT_EQ(single.step(est, goal)->region, ControlRegion::kGlobal);
}

TEST(LyapunovPoseController, RejectsNonFinitePoses) {
  LyapunovPoseController ctl;
  const double nan = std::nan("");
  auto r = ctl.step(Pose2{nan, 0.0, 0.0}, kOrigin);
  ASSERT_FALSE(r.has_value());
  EXPECT_EQ(r.error().code, "non_finite_pose");
  EXPECT_FALSE(ctl.step(kOrigin, Pose2{0.0, std::numeric_limits<double>::infinity(), 0.0}).has_value());
  EXPECT_TRUE(ctl.step(kSim1Start, kOrigin).has_value());
}

TEST(LyapunovParams, Validation) {
  EXPECT_TRUE(LyapunovParams{}.validate().has_value());
  LyapunovParams p;
  p.gains.kV = 0.0;
  EXPECT_FALSE(p.validate().has_value());
  p = {};
  p.epsRho = std::nan("");
  EXPECT_FALSE(p.validate().has_value());
  p = {};
  p.localExitFactor = 0.5;
  EXPECT_FALSE(p.validate().has_value());
}
