#include "fleet/sim/flow_field.hpp"

#include <deque>

namespace fleet::sim {

FlowField::FlowField(const GridMap& map, Vec2 goal) : goal_(goal), dist_(map.cells.size(), -1) {
  const int gx = map.cellX(goal.x);
  const int gy = map.cellY(goal.y);
  if (map.blocked(gx, gy)) {
    return;
  }
  std::deque<int> q;
  dist_[static_cast<std::size_t>(gy * map.width + gx)] = 0;
  q.push_back(gy * map.width + gx);
  while (!q.empty()) {
    const int c = q.front();
    q.pop_front();
    const int cx = c % map.width;
    const int cy = c / map.width;
    const int d = dist_[static_cast<std::size_t>(c)];
    for (const auto& [dx, dy] : {std::pair{1, 0}, std::pair{-1, 0}, std::pair{0, 1}, std::pair{0, -1}}) {
      if (!map.blocked(cx + dx, cy + dy)) {
        const auto n = static_cast<std::size_t>((cy + dy) * map.width + cx + dx);
        if (dist_[n] < 0) {
          dist_[n] = d + 1;
          q.push_back(static_cast<int>(n));
        }
      }
    }
  }
}

int FlowField::at(const GridMap& map, int cx, int cy) const {
  if (map.blocked(cx, cy)) {
    return -1;
  }
  return dist_[static_cast<std::size_t>(cy * map.width + cx)];
}

int FlowField::cellsToGoal(const GridMap& map, Vec2 p) const {
  return at(map, map.cellX(p.x), map.cellY(p.y));
}

Vec2 FlowField::direction(const GridMap& map, Vec2 p) const {
  const int cx = map.cellX(p.x);
  const int cy = map.cellY(p.y);
  const int here = at(map, cx, cy);
  if (here == 0) {
    return (goal_ - p).normalized();
  }
  int best = here < 0 ? (1 << 30) : here;
  Vec2 dir;
  for (int dy = -1; dy <= 1; ++dy) {
    for (int dx = -1; dx <= 1; ++dx) {
      if (dx == 0 && dy == 0) {
        continue;
      }
      // A diagonal step needs both orthogonal neighbours free, else people would clip shelf corners.
      if (dx != 0 && dy != 0 && (map.blocked(cx + dx, cy) || map.blocked(cx, cy + dy))) {
        continue;
      }
      const int d = at(map, cx + dx, cy + dy);
      // A free diagonal is two 4-connected steps closer, so it wins over a staircase.
      if (d >= 0 && d < best) {
        best = d;
        dir = (map.cellCenter(cx + dx, cy + dy) - p).normalized();
      }
    }
  }
  return dir;
}

}  // namespace fleet::sim
