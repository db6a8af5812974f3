#include "fleet/site/wall_segments.hpp"

namespace fleet::site {

namespace {

/// Runs of consecutive edges along one grid line that all face the same way: a run ends where an
/// edge is no face (both sides blocked or both free) or faces the other way.
template <typename IsFace>
void mergeRuns(int count, IsFace isFace, int facing, std::vector<std::pair<int, int>>& runs) {
  int start = -1;
  for (int i = 0; i <= count; ++i) {
    const bool on = i < count && isFace(i) == facing;
    if (on && start < 0) {
      start = i;
    } else if (!on && start >= 0) {
      runs.emplace_back(start, i);
      start = -1;
    }
  }
}

}  // namespace

std::vector<WallSegment> wallSegments(const planning::OccupancyGrid& map, double minLength) {
  std::vector<WallSegment> out;
  const double res = map.resolution();
  const Vec2 o = map.origin();
  std::vector<std::pair<int, int>> runs;
  // Grid line k of one direction (horizontal: between rows k-1 and k; vertical: between columns
  // k-1 and k) holds `count` edges; edge i is a face looking +1 (blocked before the line, free
  // after) or -1. The same pass serves both directions with the axes swapped.
  auto faces = [&](bool horizontal) {
    const int lines = horizontal ? map.height() : map.width();
    const int count = horizontal ? map.width() : map.height();
    auto cell = [&](int k, int i) { return horizontal ? planning::Cell{i, k} : planning::Cell{k, i}; };
    auto point = [&](int k, int i) {
      return o + (horizontal ? Vec2{i * res, k * res} : Vec2{k * res, i * res});
    };
    for (int k = 0; k <= lines; ++k) {
      auto facing = [&](int i) {
        const bool before = map.blocked(cell(k - 1, i));
        const bool after = map.blocked(cell(k, i));
        return before == after ? 0 : (before ? 1 : -1);
      };
      for (const int dir : {1, -1}) {
        runs.clear();
        mergeRuns(count, facing, dir, runs);
        const Vec2 normal = horizontal ? Vec2{0.0, double(dir)} : Vec2{double(dir), 0.0};
        for (const auto& [i0, i1] : runs) {
          const Vec2 a = point(k, i0);
          const Vec2 b = point(k, i1);
          if (distance(a, b) >= minLength) {
            out.push_back({a, b, normal});
          }
        }
      }
    }
  };
  faces(true);
  faces(false);
  return out;
}

}  // namespace fleet::site
