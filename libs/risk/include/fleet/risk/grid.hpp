#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include "fleet/risk/disc.hpp"

namespace fleet::risk {

/// Row-major cell grid in the map frame. Cell (i, j) spans [originX + i·res, originX + (i+1)·res) ×
/// [originY + j·res, …); its sample point is the cell centre. The thesis grid of N+1 points x_i = i·h
/// is GridSpec{-h/2, -h/2, h, N+1, N+1}.
struct GridSpec {
  double originX = 0.0;
  double originY = 0.0;
  double resolution = 0.1;
  int width = 0;
  int height = 0;

  [[nodiscard]] std::size_t cellCount() const {
    return static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
  }
  [[nodiscard]] std::size_t index(int i, int j) const {
    return static_cast<std::size_t>(j) * static_cast<std::size_t>(width) + static_cast<std::size_t>(i);
  }
  [[nodiscard]] double cellCentreX(int i) const {
    return originX + (static_cast<double>(i) + 0.5) * resolution;
  }
  [[nodiscard]] double cellCentreY(int j) const {
    return originY + (static_cast<double>(j) + 0.5) * resolution;
  }
  /// Cell holding the point, or nothing when the point is off the grid (or not finite).
  [[nodiscard]] std::optional<std::pair<int, int>> cellOf(double x, double y) const {
    const double fx = std::floor((x - originX) / resolution);
    const double fy = std::floor((y - originY) / resolution);
    if (!(fx >= 0.0 && fy >= 0.0 && fx < static_cast<double>(width) && fy < static_cast<double>(height))) {
      return std::nullopt;
    }
    return std::make_pair(static_cast<int>(fx), static_cast<int>(fy));
  }
  bool operator==(const GridSpec&) const = default;
};

/// The one inside test used by every algorithm that paints discs, so that the reference and the
/// fusion engine agree bit for bit (thesis step 5: (X − x)² + (Y − y)² ≤ R²).
inline bool cellInsideDisc(double cx, double cy, const Disc& d) {
  const double dx = cx - d.x;
  const double dy = cy - d.y;
  return dx * dx + dy * dy <= d.r * d.r;
}

/// Point probability p(M) of def. 3.5 sampled at the cell centres.
struct ProbabilityGrid {
  GridSpec spec;
  std::vector<double> p;  // row-major, spec.cellCount() values in [0, 1]
};

/// 3D grid of sample points (thesis §3.2.2.2 with z): point (i, j, k) = origin + (i, j, k)·resolution.
struct GridSpec3 {
  double originX = 0.0;
  double originY = 0.0;
  double originZ = 0.0;
  double resolution = 1.0;
  int nx = 0;
  int ny = 0;
  int nz = 0;

  [[nodiscard]] std::size_t cellCount() const {
    return static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny) * static_cast<std::size_t>(nz);
  }
  [[nodiscard]] std::size_t index(int i, int j, int k) const {
    return (static_cast<std::size_t>(k) * static_cast<std::size_t>(ny) + static_cast<std::size_t>(j)) *
               static_cast<std::size_t>(nx) +
           static_cast<std::size_t>(i);
  }
};

}  // namespace fleet::risk
