#include "kinematic_bound.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
#include <optional>
#include <string>

#include "fleet/site/disc_distance.hpp"

namespace fleet::ctl {

namespace {

bool valid(const BoundTask& t) {
  return t.start.isFinite() && t.pickup.isFinite() && t.dropoff.isFinite() && std::isfinite(t.radius) &&
         t.radius >= 0.0 && std::isfinite(t.cruise) && t.cruise > 0.0 && std::isfinite(t.dwellS) &&
         t.dwellS >= 0.0;
}

/// Leg lengths toward one kind of goal, computed in goal order so that each goal's distance field
/// is built once (the cache keeps two).
void legs(site::DiscDistance& free, const std::vector<BoundTask>& tasks,
          const std::vector<std::size_t>& which, bool toPickup,
          std::vector<std::optional<Expected<double>>>& out) {
  std::vector<std::size_t> order = which;
  const auto goal = [&](std::size_t i) { return toPickup ? tasks[i].pickup : tasks[i].dropoff; };
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    const Vec2 ga = goal(a), gb = goal(b);
    return ga.x < gb.x || (ga.x == gb.x && ga.y < gb.y);
  });
  for (const std::size_t i : order) {
    out[i] = free.length(toPickup ? tasks[i].start : tasks[i].pickup, goal(i));
  }
}

}  // namespace

std::vector<Expected<KinematicBound>> kinematicBounds(const planning::OccupancyGrid& freeMap,
                                                      const std::vector<BoundTask>& tasks) {
  std::vector<std::optional<Expected<double>>> toPickup(tasks.size()), toDropoff(tasks.size());
  std::map<double, std::vector<std::size_t>> byRadius;
  for (std::size_t i = 0; i < tasks.size(); ++i) {
    if (valid(tasks[i]) && freeMap.size() > 0) {
      byRadius[tasks[i].radius].push_back(i);
    }
  }
  for (const auto& [radius, which] : byRadius) {
    site::DiscDistance free(freeMap, radius, 2);
    legs(free, tasks, which, true, toPickup);
    legs(free, tasks, which, false, toDropoff);
  }
  std::vector<Expected<KinematicBound>> out;
  out.reserve(tasks.size());
  for (std::size_t i = 0; i < tasks.size(); ++i) {
    const BoundTask& t = tasks[i];
    if (!toPickup[i] || !toDropoff[i]) {
      out.emplace_back(unexpected("bad_task", freeMap.size() == 0 ? "the map is empty"
                                                                  : "cruise must be > 0 and radius and dwell "
                                                                    ">= 0, all finite, as every position"));
      continue;
    }
    if (!*toPickup[i]) {
      const auto& e = toPickup[i]->error();
      out.emplace_back(unexpected(e.code, "to the pickup: " + e.message));
      continue;
    }
    if (!*toDropoff[i]) {
      const auto& e = toDropoff[i]->error();
      out.emplace_back(unexpected(e.code, "pickup to drop-off: " + e.message));
      continue;
    }
    KinematicBound b;
    b.toPickupM = **toPickup[i];
    b.toDropoffM = **toDropoff[i];
    b.driveS = (b.toPickupM + b.toDropoffM) / t.cruise;
    b.dwellS = t.dwellS;
    out.emplace_back(b);
  }
  return out;
}

BoundFigures boundFigures(const std::vector<double>& taskS, const std::vector<double>& boundS) {
  BoundFigures f;
  f.tasks = std::min(taskS.size(), boundS.size());
  if (f.tasks == 0) {
    return f;
  }
  const auto n = static_cast<double>(f.tasks);
  f.meanTaskS = std::accumulate(taskS.begin(), taskS.begin() + static_cast<std::ptrdiff_t>(f.tasks), 0.0) / n;
  f.meanBoundS =
      std::accumulate(boundS.begin(), boundS.begin() + static_cast<std::ptrdiff_t>(f.tasks), 0.0) / n;
  if (f.meanBoundS > 0.0) {
    f.timeOverBound = f.meanTaskS / f.meanBoundS;
  }
  return f;
}

}  // namespace fleet::ctl
