#pragma once

#include "fleet/control/twist.hpp"
#include "fleet/core/expected.hpp"
#include "fleet/core/pose2.hpp"

namespace fleet::control {

/// Gains of seed 003 §4 (Sim 1 values as defaults).
struct LyapunovGains {
  double kV = 1.0;      ///< v = kV·ρ·cos α
  double kAlpha = 2.0;  ///< weight of α in ω
  double kTheta = 1.0;  ///< near-goal heading law ω = −k_θ·θe
  double h = 5.0;       ///< weight of φ in V = ρ²/2 + (α² + hφ²)/2
};

/// Polar navigation variables of seed 003 eq. 4.6 (forward direction):
/// ρ = |goal − p|, α = atan2(goal − p) − θ, φ = atan2(goal − p) − θ_goal, angles wrapped to (−π, π].
struct PolarError {
  double rho = 0.0;
  double alpha = 0.0;
  double phi = 0.0;
};

PolarError polarError(const Pose2& pose, const Pose2& goal);

/// V_G = ρ²/2 + (α² + hφ²)/2 (eq. 4.10).
double lyapunovGlobal(const PolarError& e, double h);

/// Far-field law (eq. 4.11) for a forward-driving robot: v = kV ρ cos α,
/// ω = k_α α + kV (cos α sin α / α)(α + hφ).
Twist globalLaw(const PolarError& e, const LyapunovGains& g);

enum class PoseLaw {
  kSingleLaw,  ///< eq. 4.11 everywhere (the thesis's Fig. 4.3a baseline)
  kTwoRegion,  ///< eq. 4.11 in Ω_G, the heading law of eqs. 4.20–4.22 in Ω_L
};

enum class ControlRegion { kGlobal, kLocal };

struct LyapunovParams {
  LyapunovGains gains;
  PoseLaw law = PoseLaw::kTwoRegion;
  /// Ω_L radius ε_ρ. Eq. 4.17 asks ε_ρ ≥ ε_ρ^max + ε_v^max/kV; with the thesis's ±0.1 m feedback noise
  /// (ε_ρ^max ≈ 0.14 m) and ε_v = 0.065 m/s this is ≈ 0.21 m.
  double epsRho = 0.21;
  /// Ω_L heading half-width ε_θ [rad] on |θ − θ_goal|; not in the seed (docs/algorithms.md).
  double epsTheta = 0.3;
  /// Drive backwards when the goal is behind (|α| > π/2), as the thesis's "v = −v" rule.
  bool allowReverse = true;
  /// The direction flips only once |α| passes π/2 by this margin [rad], so noisy feedback cannot chatter.
  double reverseHysteresis = 0.1;
  /// Once in Ω_L the local law stays in charge until ρ or |θe| exceed this multiple of ε_ρ / ε_θ (or the
  /// goal changes): with bounded feedback noise ρ̂ alone can cross ε_ρ while the true ρ does not.
  double localExitFactor = 2.0;

  [[nodiscard]] Expected<void> validate() const;
};

struct PoseControlOutput {
  Twist cmd;
  ControlRegion region = ControlRegion::kGlobal;
  bool reverse = false;   ///< the far-field law drove the robot backwards this step
  PolarError error;       ///< forward-direction polar error of the estimate
  double lyapunov = 0.0;  ///< V of the law in use (V_G in the driving direction, or V_L)
};

/// Lyapunov point stabilisation of a unicycle to a goal pose (seed 003 ch. 4). Holds only the driving
/// direction chosen for the current goal, so one instance serves one robot.
class LyapunovPoseController {
 public:
  explicit LyapunovPoseController(LyapunovParams params = {});

  /// One control step on the pose estimate. Error "non_finite_pose" if either pose is NaN/inf.
  Expected<PoseControlOutput> step(const Pose2& estimate, const Pose2& goal);
  /// Forget the driving direction (next step decides it afresh).
  void reset() {
    have_direction_ = false;
    in_local_ = false;
  }

  [[nodiscard]] const LyapunovParams& params() const { return params_; }

 private:
  LyapunovParams params_;
  bool have_direction_ = false;
  bool in_local_ = false;
  bool reverse_ = false;
  Pose2 direction_goal_;
  Pose2 local_goal_;
};

}  // namespace fleet::control
