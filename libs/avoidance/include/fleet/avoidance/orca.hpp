#pragma once

#include <span>
#include <vector>

#include "fleet/avoidance/local_planner.hpp"

namespace fleet::avoidance {

/// A half-plane of permitted velocities: { x : (x − point) · normal ≥ 0 }, |normal| = 1.
struct OrcaHalfPlane {
  Vec2 point;
  Vec2 normal;
};

/// ORCA half-plane of robot A against disc B (van den Berg, Guy, Lin, Manocha 2011, §IV):
/// `rel_pos` = p_B − p_A, `rel_vel` = v_A − v_B, `R` = combined radius, `tau` = time horizon,
/// `dt` = control cycle (used instead of tau once the discs already overlap), `share` = the part
/// of the escape vector u that A takes (1/2 reciprocal, 1 for non-cooperating obstacles).
OrcaHalfPlane orcaHalfPlane(Vec2 v_a, Vec2 rel_pos, Vec2 rel_vel, double R, double tau, double dt,
                            double share);

/// The velocity in the disc |v| ≤ vMax closest to `v_pref` satisfying every half-plane; when no
/// such velocity exists, the one minimising the largest violation of the planes from index
/// `hard` on (planes [0, hard) stay hard constraints). Incremental randomised-order-free 2D LP
/// with the 3D-LP fallback of the ORCA paper.
Vec2 orcaSolve(std::span<const OrcaHalfPlane> planes, std::size_t hard, Vec2 v_pref, double vMax);

struct OrcaParams {
  double tau = 2.0;        ///< horizon against other robots and humans [s]
  double tauStatic = 1.0;  ///< horizon against scan points [s]
  double margin = 0.05;    ///< added to every combined radius [m]
  /// Non-holonomic enlargement (NH-ORCA idea): the diff-drive robot only tracks the holonomic
  /// velocity with a bounded error, so its disc is grown by this tracking error bound [m].
  double trackingError = 0.05;
  double kOmega = 2.5;       ///< heading gain when tracking the holonomic velocity [1/s]
  double staticRange = 1.5;  ///< scan points farther than this are ignored [m]
  int maxStatic = 24;        ///< nearest scan points used as constraints
  /// Clockwise rotation of the preferred velocity while it is not permitted [rad]: a shared
  /// keep-right convention that breaks symmetric standoffs. 0 = textbook ORCA.
  double rightBias = 1.0;

  [[nodiscard]] Expected<void> validate() const;
};

/// Optimal reciprocal collision avoidance for a differential-drive robot: ORCA picks a holonomic
/// velocity; the robot turns towards it and drives at its speed times cos(heading error) (zero
/// when the error exceeds 90°), and the disc is enlarged by `trackingError` to cover the gap.
class OrcaPlanner final : public LocalPlanner {
 public:
  explicit OrcaPlanner(OrcaParams params = {}) : params_(params) {}
  Command plan(const LocalView& view) override;
  [[nodiscard]] std::string_view name() const override { return "orca"; }
  /// The holonomic velocity chosen in the last plan() call (world frame).
  [[nodiscard]] Vec2 lastHolonomic() const { return last_v_; }

 private:
  OrcaParams params_;
  Vec2 last_v_;
  std::vector<OrcaHalfPlane> planes_;
};

}  // namespace fleet::avoidance
