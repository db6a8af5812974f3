#include "fleet/planning/path.hpp"

#include <cmath>

namespace fleet::planning {

double Path::length() const {
  double len = 0.0;
  for (std::size_t k = 1; k < poses.size(); ++k) {
    len += distance(poses[k - 1], poses[k]);
  }
  return len;
}

Expected<CellQuery> resolveQuery(const OccupancyGrid& grid, Pose2 from, Pose2 to) {
  if (!from.isFinite() || !to.isFinite()) {
    return unexpected("invalid_pose", "start or goal pose is not finite");
  }
  const auto s = grid.cellAt(from.position());
  const auto g = grid.cellAt(to.position());
  if (!s || !g) {
    return unexpected("out_of_map", std::string(!s ? "start" : "goal") + " lies outside the map");
  }
  if (grid.blocked(*s)) {
    return unexpected("start_blocked",
                      "start cell (" + std::to_string(s->x) + ", " + std::to_string(s->y) + ") is blocked");
  }
  if (grid.blocked(*g)) {
    return unexpected("goal_blocked",
                      "goal cell (" + std::to_string(g->x) + ", " + std::to_string(g->y) + ") is blocked");
  }
  return CellQuery{*s, *g};
}

Path cellsToPath(const OccupancyGrid& grid, const std::vector<Cell>& cells, Pose2 from, Pose2 to) {
  Path path;
  std::vector<Vec2> pts{from.position()};
  for (std::size_t k = 1; k + 1 < cells.size(); ++k) {
    const Cell a = cells[k - 1], b = cells[k], c = cells[k + 1];
    if (b.x - a.x == c.x - b.x && b.y - a.y == c.y - b.y) {
      continue;  // collinear: not a corner
    }
    pts.push_back(grid.cellCenter(b));
  }
  pts.push_back(to.position());
  for (std::size_t k = 0; k < pts.size(); ++k) {
    double theta = 0.0;
    if (k == 0) {
      theta = from.theta;
    } else if (k + 1 == pts.size()) {
      theta = to.theta;
    } else {
      const Vec2 d = pts[k + 1] - pts[k];
      theta = std::atan2(d.y, d.x);
    }
    path.poses.push_back({pts[k].x, pts[k].y, theta});
  }
  return path;
}

}  // namespace fleet::planning
