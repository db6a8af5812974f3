#pragma once

#include <cmath>

namespace fleet::risk {

/// A disc O(M, r) of the thesis (def. 3.3) in the map frame, with the standard deviation of its
/// centre position (isotropic, metres). The overlap-ratio model ignores sigma.
struct Disc {
  double x = 0.0;
  double y = 0.0;
  double r = 0.0;
  double sigma = 0.0;
};

/// A sphere O(M, r) for the 3D variant of the thesis formulas.
struct Sphere {
  double x = 0.0;
  double y = 0.0;
  double z = 0.0;
  double r = 0.0;
};

// sqrt rather than hypot: coordinates are bounded (validated), and this is on the hot path.
inline double centreDistance(const Disc& a, const Disc& b) {
  const double dx = a.x - b.x;
  const double dy = a.y - b.y;
  return std::sqrt(dx * dx + dy * dy);
}

inline double centreDistance(const Sphere& a, const Sphere& b) {
  const double dx = a.x - b.x;
  const double dy = a.y - b.y;
  const double dz = a.z - b.z;
  return std::sqrt(dx * dx + dy * dy + dz * dz);
}

}  // namespace fleet::risk
