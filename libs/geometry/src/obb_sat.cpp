#include <Eigen/Dense>
#include <cmath>

#include "fleet/geometry/obb.hpp"

namespace fleet::geometry {

bool Obb3::contains(const Eigen::Vector3d& p, double tol) const {
  const Eigen::Vector3d local = axes.transpose() * (p - center);
  return (local.array().abs() <= half.array() + tol).all();
}

SatResult satTest(const Obb3& a, const Obb3& b, double eps) {
  SatResult res;
  const Eigen::Matrix3d c = a.axes.transpose() * b.axes;  // c_ij = A_i . B_j  (2.10)
  const Eigen::Matrix3d absC = c.cwiseAbs().array() + eps;
  const Eigen::Vector3d d = b.center - a.center;
  const Eigen::Vector3d ad = a.axes.transpose() * d;  // A_i . D
  const Eigen::Vector3d& ah = a.half;
  const Eigen::Vector3d& bh = b.half;

  for (int i = 0; i < 3; ++i) {
    ++res.axesTested;
    const double r1 = bh.dot(absC.row(i));
    if (std::abs(ad(i)) > ah(i) + r1) {
      res.separatingAxis = i;
      return res;
    }
  }
  for (int j = 0; j < 3; ++j) {
    ++res.axesTested;
    const double r = std::abs(c.col(j).dot(ad));  // B_j . D
    const double r0 = ah.dot(absC.col(j));
    if (r > r0 + bh(j)) {
      res.separatingAxis = 3 + j;
      return res;
    }
  }
  for (int i = 0; i < 3; ++i) {
    const int i1 = (i + 1) % 3;
    const int i2 = (i + 2) % 3;
    for (int j = 0; j < 3; ++j) {
      const int j1 = (j + 1) % 3;
      const int j2 = (j + 2) % 3;
      ++res.axesTested;
      // V = A_i x B_j = c_{i1 j} A_{i2} - c_{i2 j} A_{i1}: the general cyclic form of Table 2.1.
      const double r = std::abs(c(i1, j) * ad(i2) - c(i2, j) * ad(i1));
      const double r0 = ah(i1) * absC(i2, j) + ah(i2) * absC(i1, j);
      const double r1 = bh(j1) * absC(i, j2) + bh(j2) * absC(i, j1);
      if (r > r0 + r1) {
        res.separatingAxis = 6 + 3 * i + j;
        return res;
      }
    }
  }
  res.intersect = true;
  return res;
}

bool overlaps(const Obb2& a, const Obb2& b) {
  const Vec2 au[2] = {{std::cos(a.angle), std::sin(a.angle)}, {-std::sin(a.angle), std::cos(a.angle)}};
  const Vec2 bu[2] = {{std::cos(b.angle), std::sin(b.angle)}, {-std::sin(b.angle), std::cos(b.angle)}};
  const double ah[2] = {a.half.x, a.half.y};
  const double bh[2] = {b.half.x, b.half.y};
  const Vec2 d = b.center - a.center;
  for (int k = 0; k < 4; ++k) {
    const Vec2 v = k < 2 ? au[k] : bu[k - 2];
    const double r0 = ah[0] * std::abs(au[0].dot(v)) + ah[1] * std::abs(au[1].dot(v));
    const double r1 = bh[0] * std::abs(bu[0].dot(v)) + bh[1] * std::abs(bu[1].dot(v));
    if (std::abs(d.dot(v)) > r0 + r1) {
      return false;
    }
  }
  return true;
}

}  // namespace fleet::geometry
