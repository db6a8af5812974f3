#pragma once

// The world's own random draws and its fast vector length, shared by its files (world.cpp,
// world_humans.cpp, world_sensors.cpp).

#include <algorithm>
#include <cmath>
#include <random>

#include "fleet/core/angles.hpp"
#include "fleet/sim/world.hpp"

namespace fleet::sim::world_detail {

// Our own normal/uniform draws: std:: distributions are implementation-defined, these are not.
inline double uniform01(std::mt19937_64& g) {
  return static_cast<double>(g() >> 11) * 0x1.0p-53;
}
inline double normal(GaussianStream& g, double sigma) {
  if (sigma <= 0.0) {
    return 0.0;
  }
  if (g.hasSpare) {
    g.hasSpare = false;
    return sigma * g.spare;
  }
  // Box-Muller: both outputs are used, the second one cached for the next draw.
  const double u1 = std::max(uniform01(g.engine), 1e-300);
  const double u2 = uniform01(g.engine);
  const double rho = std::sqrt(-2.0 * std::log(u1));
  g.spare = rho * std::sin(2.0 * kPi * u2);
  g.hasSpare = true;
  return sigma * rho * std::cos(2.0 * kPi * u2);
}
inline double uniform01(GaussianStream& g) {
  return uniform01(g.engine);
}

// std::hypot (behind Vec2::norm) guards against overflow we cannot have at warehouse scale, at
// several times the cost of a square root; this is the hot path of scans and contacts.
inline double len(Vec2 v) {
  return std::sqrt(v.squaredNorm());
}

}  // namespace fleet::sim::world_detail
