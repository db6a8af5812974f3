#pragma once

#include <span>
#include <vector>

#include "fleet/avoidance/local_planner.hpp"
#include "fleet/geometry/obb.hpp"

namespace fleet::avoidance {

/// Internal (contraction) force of seed 000 eq. 2.16 on control point P^j between P^{j−1} and
/// P^{j+1}: kC·( d⁻/(d⁻ + d⁺)·(P^{j+1} − P^{j−1}) − (P^j − P^{j−1}) ).
Vec2 elasticInternalForce(Vec2 prev, Vec2 cur, Vec2 next, double kC);

/// External force of eq. 2.21: K_r·(threshold − d_obs,min)·(P_m − P_o)/|P_m − P_o| when
/// d_obs,min < threshold, else 0. The original uses threshold d_o = dSafe + d_r; the thesis's
/// two-sided variant (2.27) uses dSafe.
Vec2 elasticExternalForce(Vec2 robot, Vec2 obstacle, double d_obs_min, double threshold, double kR);

/// The thesis's obstacle-box scan (§2.3.1): nearest reading below dSafe in the first half of the
/// scan (left) and in the second half (right); both start at dSafe.
struct LeftRightMinimum {
  double minLeft = 0.0;
  double minRight = 0.0;
  int leftIndex = -1;
  int rightIndex = -1;
  bool found = false;  ///< false when no reading is below dSafe (the thesis's FALSE)
};
LeftRightMinimum leftRightMinimum(std::span<const double> ranges, double dSafe);

/// The thesis's boxes (§2.3.1, Figs. 2.22-2.23): OBB-O spans the nearest left reading L, the nearest
/// right reading R, and both moved dSafe along the direction of motion `heading` (unit); OBB-R is
/// the robot's footprint swept over the step: width 2r, from r behind `robot` to r past `next`.
geometry::Obb2 obstacleBox(Vec2 left, Vec2 right, Vec2 heading, double dSafe);
geometry::Obb2 robotBox(Vec2 robot, Vec2 next, Vec2 heading, double radius);

enum class ElasticVariant { kOriginal, kBvhTwoSided };

/// Parameters in metres; defaults = Table 2.3 case 1 (K_c 0.8, K_r 0.6, dSafe 1000 mm, d_r 350 mm).
struct ElasticStripsParams {
  double kC = 0.8;
  double kR = 0.6;
  double dSafe = 1.0;
  double spacing = 0.3;  ///< control-point spacing of the strip [m]
  double kOmega = 2.0;
  int beams = 72;  ///< the two-sided variant bins the scan into this many bearings

  [[nodiscard]] Expected<void> validate() const;
};

/// Elastic Strips turned into a (v, ω) planner: each cycle the strip is rebuilt from the robot
/// along the path, the next control point is displaced by F = F_int + F_ext (eq. 2.24: new
/// point = planned point + F), and the robot steers to the displaced point (heading
/// atan2(Δy, Δx), the fix of eq. 2.26 noted in docs/algorithms.md).
class ElasticStripsPlanner final : public LocalPlanner {
 public:
  explicit ElasticStripsPlanner(ElasticVariant variant, ElasticStripsParams params = {})
      : variant_(variant), params_(params) {}
  Command plan(const LocalView& view) override;
  [[nodiscard]] std::string_view name() const override {
    return variant_ == ElasticVariant::kOriginal ? "elastic_strips" : "elastic_strips_bvh";
  }
  void reset() override { have_prev_ = false; }

  /// The displaced next control point of the last plan() and the force applied to it.
  [[nodiscard]] Vec2 lastTarget() const { return target_; }
  [[nodiscard]] Vec2 lastForce() const { return force_; }
  /// Two-sided variant, last plan(): how the external force was decided.
  enum class Contact {
    kNone,        ///< no reading within dSafe: no external force
    kOnePoint,    ///< one side only: the original's single-reading force (the thesis's rule)
    kBoxesApart,  ///< readings on both sides, but OBB-R does not meet OBB-O: no external force
    kBoxesMeet,   ///< readings on both sides and the boxes overlap: the two forces (2.27, 2.28)
  };
  [[nodiscard]] Contact lastContact() const { return contact_; }

 private:
  [[nodiscard]] Vec2 externalForce(const LocalView& view, Vec2 at);

  ElasticVariant variant_;
  ElasticStripsParams params_;
  bool have_prev_ = false;
  Vec2 prev_;
  Vec2 target_;
  Vec2 force_;
  Contact contact_ = Contact::kNone;
  std::vector<double> ranges_;
  std::vector<Vec2> hits_;
};

}  // namespace fleet::avoidance
