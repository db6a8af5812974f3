#include "map_faces.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

namespace fleet::agent {

std::vector<Vec2> mapFaces(const planning::OccupancyGrid& map, Vec2 here, double range) {
  std::vector<Vec2> pts;
  const double res = map.resolution();
  const int reach = static_cast<int>(std::ceil(range / res));
  const Vec2 rel = (here - map.origin()) * (1.0 / res);
  const int cx = static_cast<int>(std::floor(rel.x));
  const int cy = static_cast<int>(std::floor(rel.y));
  // Points every ~0.1 m along each face a blocked cell shares with a free one.
  const int perEdge = std::max(1, static_cast<int>(std::ceil(res / 0.1)));
  for (int y = cy - reach; y <= cy + reach; ++y) {
    for (int x = cx - reach; x <= cx + reach; ++x) {
      const planning::Cell c{x, y};
      if (!map.inside(c) || !map.blocked(c)) {
        continue;
      }
      const Vec2 lo = map.origin() + Vec2{x * res, y * res};
      for (const auto& [dx, dy] : {std::pair{1, 0}, std::pair{-1, 0}, std::pair{0, 1}, std::pair{0, -1}}) {
        if (map.blocked({x + dx, y + dy})) {
          continue;
        }
        // The shared face: from a to b.
        const Vec2 a = lo + Vec2{dx > 0 ? res : 0.0, dy > 0 ? res : 0.0};
        const Vec2 b = a + (dx != 0 ? Vec2{0.0, res} : Vec2{res, 0.0});
        if ((here - a).dot(Vec2{static_cast<double>(dx), static_cast<double>(dy)}) <= 0.0) {
          // Turned away from the robot: the far side of its own obstacle, which the robot can
          // only reach through a face turned towards it. (Half the points: the local planner's
          // cost grows with them.)
          continue;
        }
        for (int k = 0; k <= perEdge; ++k) {
          const Vec2 q = a + (b - a) * (static_cast<double>(k) / perEdge);
          if (distance(q, here) < range) {
            pts.push_back(q);
          }
        }
      }
    }
  }
  return pts;
}

}  // namespace fleet::agent
