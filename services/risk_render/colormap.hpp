#pragma once

#include <algorithm>
#include <cstdint>

namespace fleet::risk_render {

struct Rgb {
  std::uint8_t r, g, b;
};

/// Piecewise-linear approximation of the viridis colour map on [0, 1].
inline Rgb viridis(double t) {
  static constexpr double kStops[6][3] = {{68, 1, 84},   {59, 82, 139},  {33, 145, 140},
                                          {94, 201, 98}, {189, 223, 38}, {253, 231, 37}};
  t = std::clamp(t, 0.0, 1.0) * 5.0;
  const int k = std::min(4, static_cast<int>(t));
  const double f = t - k;
  auto mix = [&](int c) {
    return static_cast<std::uint8_t>(kStops[k][c] + (kStops[k + 1][c] - kStops[k][c]) * f + 0.5);
  };
  return {mix(0), mix(1), mix(2)};
}

}  // namespace fleet::risk_render
