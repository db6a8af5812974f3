#include "fleet/traffic/station_cycle.hpp"

#include <algorithm>
#include <cmath>

namespace fleet::traffic {

double dockMoveSeconds(const DockGeometry& g, double radius, double cruise) {
  if (!(cruise > 0.0) || !std::isfinite(cruise) || !std::isfinite(radius) || radius < 0.0) {
    return 0.0;
  }
  const Vec2 a = g.approach.value_or(g.dock);
  const double leg = (g.dock - a).norm();
  if (g.exit) {
    const double wait = g.queue.empty() ? 2.0 * radius : (g.queue.front() - a).norm();
    const double s = (leg + wait) / cruise;
    return std::isfinite(s) ? s : 0.0;
  }
  const double wait = g.queue.empty() ? 2.0 * radius : std::max((g.queue.front() - a).norm(), 2.0 * radius);
  const double s = (2.0 * leg + wait) / cruise;
  return std::isfinite(s) ? s : 0.0;
}

DockGeometry dockGeometry(const Graph& g, const StationNodes& s) {
  DockGeometry geo{g.position(s.dock), std::nullopt, {}, std::nullopt};
  if (s.approach != kNoNode) {
    geo.approach = g.position(s.approach);
  }
  if (!s.queue.empty()) {
    geo.queue.push_back(g.position(s.queue.front()));
  }
  if (s.exit != kNoNode) {
    geo.exit = g.position(s.exit);
  }
  return geo;
}

}  // namespace fleet::traffic
