#include "fleet/sim/spatial_hash.hpp"

#include <algorithm>
#include <cmath>

namespace fleet::sim {

SpatialHash::SpatialHash(Vec2 lo, Vec2 hi, double cell)
    : lo_(lo),
      inv_(1.0 / cell),
      nx_(std::max(1, static_cast<int>(std::ceil((hi.x - lo.x) / cell)))),
      ny_(std::max(1, static_cast<int>(std::ceil((hi.y - lo.y) / cell)))) {
  start_.assign(static_cast<std::size_t>(nx_) * static_cast<std::size_t>(ny_) + 1, 0);
}

int SpatialHash::bx(double x) const {
  const double c = std::floor((x - lo_.x) * inv_);
  return static_cast<int>(std::clamp(c, 0.0, static_cast<double>(nx_ - 1)));
}
int SpatialHash::by(double y) const {
  const double c = std::floor((y - lo_.y) * inv_);
  return static_cast<int>(std::clamp(c, 0.0, static_cast<double>(ny_ - 1)));
}

void SpatialHash::build(const std::vector<Vec2>& points) {
  std::fill(start_.begin(), start_.end(), 0);
  bucketOf_.resize(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    const int b = by(points[i].y) * nx_ + bx(points[i].x);
    bucketOf_[i] = b;
    ++start_[static_cast<std::size_t>(b) + 1];
  }
  for (std::size_t b = 1; b < start_.size(); ++b) {
    start_[b] += start_[b - 1];
  }
  items_.resize(points.size());
  std::vector<int> fill(start_.begin(), start_.end() - 1);
  for (std::size_t i = 0; i < points.size(); ++i) {
    items_[static_cast<std::size_t>(fill[static_cast<std::size_t>(bucketOf_[i])]++)] = static_cast<int>(i);
  }
}

}  // namespace fleet::sim
