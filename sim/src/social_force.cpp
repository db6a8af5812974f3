#include "fleet/sim/social_force.hpp"

#include <algorithm>
#include <cmath>

namespace fleet::sim {

Vec2 drivingForce(Vec2 desiredVelocity, Vec2 velocity, double tau) {
  return (desiredVelocity - velocity) / tau;
}

Vec2 bodyRepulsion(double A, double B, double lambda, Vec2 pi, double ri, Vec2 heading, Vec2 pj, double rj) {
  const Vec2 diff = pi - pj;
  const double d = std::sqrt(diff.squaredNorm());  // hypot's overflow guard is not needed here
  const Vec2 n = d > 0.0 ? diff / d : Vec2{1.0, 0.0};
  const double cosPhi = -n.dot(heading);  // heading · (direction from i to j)
  const double w = heading.squaredNorm() > 0.0 ? lambda + (1.0 - lambda) * 0.5 * (1.0 + cosPhi) : 1.0;
  // Overlapping bodies also get Helbing's (2000) contact term k·(ri + rj − d): without it a crowd
  // converging on one point compresses until people pass through each other.
  const double overlap = std::max(0.0, ri + rj - d);
  return n * (A * std::exp((ri + rj - d) / B) * w + kBodyStiffness * overlap);
}

Vec2 wallRepulsion(double A, double B, double ri, double dist, Vec2 away) {
  return away * (A * std::exp((ri - dist) / B));
}

}  // namespace fleet::sim
