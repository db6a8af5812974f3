#pragma once

#include <vector>

#include "fleet/core/vec2.hpp"

namespace fleet::sim {

/// Uniform bucket grid over a rectangle, rebuilt every step (counting sort: O(n), no allocation once warm).
/// Points outside the rectangle go to the border buckets, so queries stay correct, only slower.
class SpatialHash {
 public:
  SpatialHash(Vec2 lo, Vec2 hi, double cell);
  void build(const std::vector<Vec2>& points);
  /// Calls f(index) for every point whose bucket touches the square of half-side `radius` around p
  /// (a superset of the points within `radius`), in increasing bucket then insertion order.
  template <class F>
  void forEachNear(Vec2 p, double radius, F&& f) const {
    const int x0 = bx(p.x - radius);
    const int x1 = bx(p.x + radius);
    const int y0 = by(p.y - radius);
    const int y1 = by(p.y + radius);
    for (int y = y0; y <= y1; ++y) {
      for (int x = x0; x <= x1; ++x) {
        const std::size_t b =
            static_cast<std::size_t>(y) * static_cast<std::size_t>(nx_) + static_cast<std::size_t>(x);
        for (int k = start_[b]; k < start_[b + 1]; ++k) {
          f(items_[static_cast<std::size_t>(k)]);
        }
      }
    }
  }

 private:
  [[nodiscard]] int bx(double x) const;
  [[nodiscard]] int by(double y) const;
  Vec2 lo_;
  double inv_;
  int nx_;
  int ny_;
  std::vector<int> start_;
  std::vector<int> items_;
  std::vector<int> bucketOf_;
};

}  // namespace fleet::sim
