#pragma once

#include <Eigen/Core>
#include <optional>

#include "fleet/core/vec2.hpp"

namespace fleet::geometry {

/// Oriented box in space (thesis (2.3)): centre, orthonormal right-handed axes as the columns of
/// `axes`, and HALF extents along them.
struct Obb3 {
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  Eigen::Matrix3d axes = Eigen::Matrix3d::Identity();
  Eigen::Vector3d half = Eigen::Vector3d::Ones();

  [[nodiscard]] bool contains(const Eigen::Vector3d& p, double tol = 0.0) const;
  [[nodiscard]] Obb3 translated(const Eigen::Vector3d& d) const {
    Obb3 o = *this;
    o.center += d;
    return o;
  }
};

/// Oriented rectangle in the plane: centre, heading of its first axis, half extents.
struct Obb2 {
  Vec2 center;
  double angle = 0.0;
  Vec2 half{1.0, 1.0};
};

/// Axis numbering of the 15 candidate axes: 0..2 = A_i, 3..5 = B_j, 6 + 3i + j = A_i x B_j.
struct SatResult {
  bool intersect = false;
  int separatingAxis = -1;  ///< first axis with R > R0 + R1, or -1 when intersecting
  int axesTested = 0;
};

/// Level 1 of the thesis: separating-axis test over the 15 axes (Table 2.1 with |.| on R).
/// Touching boxes (R == R0 + R1) intersect. `eps` is added to every |c_ij| so that near-parallel
/// edges (V ~ 0) never report a false separation.
SatResult satTest(const Obb3& a, const Obb3& b, double eps = 1e-12);

/// Level 2: a contact point of two touching boxes, given the axis along which they touch (the last
/// separating axis before contact). Uses the derived cyclic formulas (docs/algorithms.md), not the
/// printed Table 2.2. Face-face and edge-face contacts pick one point of the contact patch.
Eigen::Vector3d contactPoint(const Obb3& a, const Obb3& b, int axis);

/// First contact of two boxes moving at constant velocities, sampled every dt up to tmax (the thesis
/// scheme), then refined by bisection between the last separated and first intersecting sample.
struct FirstContact {
  double time = 0.0;  ///< last time at which the boxes are still separated (to ~1e-12 dt)
  int axis = -1;      ///< separating axis at that time
  Eigen::Vector3d point = Eigen::Vector3d::Zero();
};
std::optional<FirstContact> firstContact(const Obb3& a, const Eigen::Vector3d& va, const Obb3& b,
                                         const Eigen::Vector3d& vb, double dt, double tmax);

/// 2-D separating-axis test (4 axes); touching counts as overlap.
bool overlaps(const Obb2& a, const Obb2& b);

}  // namespace fleet::geometry
