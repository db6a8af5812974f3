#include <Eigen/Dense>
#include <cmath>

#include "fleet/geometry/obb.hpp"

namespace fleet::geometry {

namespace {

double sgn(double v) {
  return v > 0.0 ? 1.0 : (v < 0.0 ? -1.0 : 0.0);
}

Eigen::Vector3d clampToBox(const Obb3& box, const Eigen::Vector3d& p) {
  Eigen::Vector3d local = box.axes.transpose() * (p - box.center);
  local = local.cwiseMax(-box.half).cwiseMin(box.half);
  return box.center + box.axes * local;
}

// Face-face and edge-face contacts have a whole patch of contact points; the formulas fix only some
// coordinates. Alternating projections between the two closed boxes converge to a point of their
// intersection (the patch), starting from the formula's point.
Eigen::Vector3d settleInPatch(const Obb3& a, const Obb3& b, Eigen::Vector3d p) {
  for (int k = 0; k < 400; ++k) {
    const Eigen::Vector3d pa = clampToBox(a, p);
    const Eigen::Vector3d pb = clampToBox(b, pa);
    if ((pb - p).squaredNorm() == 0.0) {
      break;
    }
    p = pb;
  }
  return p;
}

}  // namespace

Eigen::Vector3d contactPoint(const Obb3& a, const Obb3& b, int axis) {
  const Eigen::Matrix3d c = a.axes.transpose() * b.axes;
  const Eigen::Vector3d d = b.center - a.center;
  const Eigen::Vector3d ad = a.axes.transpose() * d;  // A_i . D
  const Eigen::Vector3d bd = b.axes.transpose() * d;  // B_j . D
  const double scale = 1e-12;
  Eigen::Vector3d x = Eigen::Vector3d::Zero();  // coordinates of P in A's frame
  Eigen::Vector3d y = Eigen::Vector3d::Zero();  // coordinates of P in B's frame
  bool degenerate = false;

  if (axis >= 0 && axis < 3) {
    const int i = axis;
    const double sigma = ad(i) >= 0.0 ? 1.0 : -1.0;
    for (int j = 0; j < 3; ++j) {
      if (std::abs(c(i, j)) > scale) {
        y(j) = -sigma * sgn(c(i, j)) * b.half(j);
      } else {
        degenerate = true;
        y(j) = std::clamp(-bd(j), -b.half(j), b.half(j));
      }
    }
    const Eigen::Vector3d p = b.center + b.axes * y;
    return degenerate ? settleInPatch(a, b, p) : p;
  }
  if (axis >= 3 && axis < 6) {
    const int j = axis - 3;
    const double sigma = bd(j) >= 0.0 ? 1.0 : -1.0;
    // Projecting (2.12) on B_j: x_k = +sigma sgn(c_kj) a_k (the printed case 2 has the sign and the
    // index order wrong).
    for (int k = 0; k < 3; ++k) {
      if (std::abs(c(k, j)) > scale) {
        x(k) = sigma * sgn(c(k, j)) * a.half(k);
      } else {
        degenerate = true;
        x(k) = std::clamp(ad(k), -a.half(k), a.half(k));
      }
    }
    const Eigen::Vector3d p = a.center + a.axes * x;
    return degenerate ? settleInPatch(a, b, p) : p;
  }
  const int i = (axis - 6) / 3;
  const int j = (axis - 6) % 3;
  const int i1 = (i + 1) % 3;
  const int i2 = (i + 2) % 3;
  const int j1 = (j + 1) % 3;
  const int j2 = (j + 2) % 3;
  const double vd = c(i1, j) * ad(i2) - c(i2, j) * ad(i1);
  const double sigma = vd >= 0.0 ? 1.0 : -1.0;
  x(i1) = -sigma * sgn(c(i2, j)) * a.half(i1);
  x(i2) = sigma * sgn(c(i1, j)) * a.half(i2);
  y(j1) = -sigma * sgn(c(i, j2)) * b.half(j1);
  y(j2) = sigma * sgn(c(i, j1)) * b.half(j2);
  const double denom = 1.0 - c(i, j) * c(i, j);
  if (denom < 1e-9 || std::abs(c(i2, j)) <= scale || std::abs(c(i1, j)) <= scale ||
      std::abs(c(i, j2)) <= scale || std::abs(c(i, j1)) <= scale) {
    degenerate = true;
  }
  if (denom > 1e-12) {
    x(i) = (ad(i) + c(i, j) * (-bd(j) + c(i1, j) * x(i1) + c(i2, j) * x(i2)) + c(i, j1) * y(j1) +
            c(i, j2) * y(j2)) /
           denom;
  }
  const Eigen::Vector3d p = a.center + a.axes * x;
  return degenerate ? settleInPatch(a, b, p) : p;
}

std::optional<FirstContact> firstContact(const Obb3& a, const Eigen::Vector3d& va, const Obb3& b,
                                         const Eigen::Vector3d& vb, double dt, double tmax) {
  auto at = [&](double t) { return satTest(a.translated(t * va), b.translated(t * vb)); };
  if (at(0.0).intersect || !(dt > 0.0)) {
    return std::nullopt;
  }
  double lo = 0.0;
  double hi = -1.0;
  for (double t = dt; t <= tmax + 1e-12 * dt; t += dt) {
    if (at(t).intersect) {
      hi = t;
      break;
    }
    lo = t;
  }
  if (hi < 0.0) {
    return std::nullopt;
  }
  // The thesis stops at the last separated sample; bisection removes the sampling error.
  for (int k = 0; k < 60 && hi - lo > 1e-12 * dt; ++k) {
    const double mid = 0.5 * (lo + hi);
    (at(mid).intersect ? hi : lo) = mid;
  }
  FirstContact fc;
  fc.time = lo;
  fc.axis = at(lo).separatingAxis;
  fc.point = contactPoint(a.translated(hi * va), b.translated(hi * vb), fc.axis);
  return fc;
}

}  // namespace fleet::geometry
