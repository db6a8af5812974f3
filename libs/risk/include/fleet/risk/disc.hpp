#pragma once

#include <cmath>

namespace fleet::risk {

/// Symmetric 2×2 covariance [[xx, xy], [xy, yy]] (m²).
struct Cov2 {
  double xx = 0.0;
  double xy = 0.0;
  double yy = 0.0;
  bool operator==(const Cov2&) const = default;
};

/// Largest eigenvalue of a symmetric 2×2 matrix (0 for a zero matrix).
inline double largestEigenvalue(const Cov2& c) {
  const double half = 0.5 * (c.xx - c.yy);
  return 0.5 * (c.xx + c.yy) + std::sqrt(half * half + c.xy * c.xy);
}

/// A disc O(M, r) of the thesis (def. 3.3) in the map frame, with the uncertainty of its centre:
/// either isotropic (standard deviation `sigma`, m; `cov` all zero) or anisotropic (`cov`, m², whose
/// trace is then > 0; sigma is ignored by the Gaussian model and should be √λmax(cov), what a reader
/// that knows only σ would use). The overlap-ratio model ignores both.
struct Disc {
  double x = 0.0;
  double y = 0.0;
  double r = 0.0;
  double sigma = 0.0;
  Cov2 cov{};

  [[nodiscard]] bool anisotropic() const { return cov.xx + cov.yy > 0.0; }
  /// The centre's covariance either way.
  [[nodiscard]] Cov2 covariance() const {
    return anisotropic() ? cov : Cov2{sigma * sigma, 0.0, sigma * sigma};
  }
  /// Standard deviation along the most uncertain direction.
  [[nodiscard]] double sigmaMax() const { return anisotropic() ? std::sqrt(largestEigenvalue(cov)) : sigma; }
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
