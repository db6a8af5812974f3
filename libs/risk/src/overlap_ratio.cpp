#include "fleet/risk/overlap_ratio.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <utility>

namespace fleet::risk {
namespace {

constexpr double kPi = std::numbers::pi;

// Distance from centre 1 to the radical line (the thesis's x = M1K). Requires d > 0.
double chordOffset(double r1, double r2, double d) {
  return (r1 * r1 + d * d - r2 * r2) / (2.0 * d);
}

}  // namespace

double discIntersectionArea(double r1, double r2, double d) {
  if (r1 < r2) {
    std::swap(r1, r2);  // one argument order, so the result is bitwise symmetric
  }
  if (!(r1 > 0.0) || !(r2 > 0.0) || d >= r1 + r2) {
    return 0.0;
  }
  const double rmin = std::min(r1, r2);
  if (d <= std::abs(r1 - r2)) {
    return kPi * rmin * rmin;
  }
  const double x1 = chordOffset(r1, r2, d);
  const double x2 = d - x1;
  // Half chord z; (r1 - x1)(r1 + x1) avoids the cancellation of r1² − x1² near tangency.
  const double z = std::sqrt(std::max(0.0, (r1 - x1) * (r1 + x1)));
  // Half-angles of the sectors; atan2 stays accurate where acos(x/r) near ±1 would not.
  const double a1 = std::atan2(z, x1);
  const double a2 = std::atan2(z, x2);
  const double area = r1 * r1 * a1 - x1 * z + r2 * r2 * a2 - x2 * z;
  return std::clamp(area, 0.0, kPi * rmin * rmin);
}

namespace {
// The overlap ratio given inter = discIntersectionArea(r1, r2, d), shared by both entry points so that
// they agree bit for bit.
double overlapRatioFromArea(double r1, double r2, double d, double inter) {
  if (r1 < r2) {
    std::swap(r1, r2);  // one argument order, so the result is bitwise symmetric
  }
  if (!(r1 > 0.0) || !(r2 > 0.0) || d >= r1 + r2) {
    return 0.0;
  }
  if (d <= std::abs(r1 - r2)) {
    const double q = std::min(r1, r2) / std::max(r1, r2);
    return q * q;
  }
  const double uni = kPi * (r1 * r1 + r2 * r2) - inter;
  return std::clamp(inter / uni, 0.0, 1.0);
}

}  // namespace

double discOverlapRatio(double r1, double r2, double d) {
  if (!(r1 > 0.0) || !(r2 > 0.0) || d >= r1 + r2) {
    return 0.0;
  }
  return overlapRatioFromArea(r1, r2, d, discIntersectionArea(r1, r2, d));
}

double sphereIntersectionVolume(double r1, double r2, double d) {
  if (r1 < r2) {
    std::swap(r1, r2);  // one argument order, so the result is bitwise symmetric
  }
  if (!(r1 > 0.0) || !(r2 > 0.0) || d >= r1 + r2) {
    return 0.0;
  }
  const double rmin = std::min(r1, r2);
  const double vmin = 4.0 / 3.0 * kPi * rmin * rmin * rmin;
  if (d <= std::abs(r1 - r2)) {
    return vmin;
  }
  const double x1 = chordOffset(r1, r2, d);
  const double h1 = r1 - x1;  // cap heights (the thesis's corrected h1, h2)
  const double h2 = r2 - (d - x1);
  const double v = kPi * h1 * h1 * (r1 - h1 / 3.0) + kPi * h2 * h2 * (r2 - h2 / 3.0);
  return std::clamp(v, 0.0, vmin);
}

double sphereOverlapRatio(double r1, double r2, double d) {
  if (r1 < r2) {
    std::swap(r1, r2);  // one argument order, so the result is bitwise symmetric
  }
  if (!(r1 > 0.0) || !(r2 > 0.0) || d >= r1 + r2) {
    return 0.0;
  }
  if (d <= std::abs(r1 - r2)) {
    const double q = std::min(r1, r2) / std::max(r1, r2);
    return q * q * q;
  }
  const double inter = sphereIntersectionVolume(r1, r2, d);
  const double uni = 4.0 / 3.0 * kPi * (r1 * r1 * r1 + r2 * r2 * r2) - inter;
  return std::clamp(inter / uni, 0.0, 1.0);
}

double sceneOverlapRatio(std::span<const Disc> discs) {
  double num = 0.0;
  double den = 0.0;
  for (std::size_t i = 0; i < discs.size(); ++i) {
    for (std::size_t j = i + 1; j < discs.size(); ++j) {
      const double inter = discIntersectionArea(discs[i].r, discs[j].r, centreDistance(discs[i], discs[j]));
      num += inter;
      den += kPi * (discs[i].r * discs[i].r + discs[j].r * discs[j].r) - inter;
    }
  }
  // Σ over i≠j counts every unordered pair twice in both sums; the factor cancels.
  return den > 0.0 ? std::clamp(num / den, 0.0, 1.0) : 0.0;
}

double sceneOverlapRatio(std::span<const Sphere> spheres) {
  double num = 0.0;
  double den = 0.0;
  for (std::size_t i = 0; i < spheres.size(); ++i) {
    for (std::size_t j = i + 1; j < spheres.size(); ++j) {
      const double ri = spheres[i].r;
      const double rj = spheres[j].r;
      const double inter = sphereIntersectionVolume(ri, rj, centreDistance(spheres[i], spheres[j]));
      num += inter;
      den += 4.0 / 3.0 * kPi * (ri * ri * ri + rj * rj * rj) - inter;
    }
  }
  return den > 0.0 ? std::clamp(num / den, 0.0, 1.0) : 0.0;
}

double OverlapRatio::pair(const Disc& a, const Disc& b) const {
  return discOverlapRatio(a.r, b.r, centreDistance(a, b));
}

double OverlapRatio::pairWithIntersection(const Disc& a, const Disc& b, double d,
                                          double intersectionArea) const {
  return overlapRatioFromArea(a.r, b.r, d, intersectionArea);
}

double OverlapRatio::cullDistance(const Disc& a, const Disc& b) const {
  return a.r + b.r;
}

double OverlapRatio::reach(const Disc& a) const {
  return a.r;
}

}  // namespace fleet::risk
