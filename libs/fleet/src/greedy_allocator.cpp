#include <algorithm>
#include <cmath>
#include <numeric>

#include "fleet/core/clock.hpp"
#include "fleet/fleet/allocator.hpp"

namespace fleet {

std::vector<Assignment> GreedyAllocator::assign(std::span<const Task> tasks,
                                                std::span<const RobotInfo> robots, const TravelModel& travel,
                                                std::int64_t nowNs) const {
  std::vector<std::size_t> order(tasks.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  auto deadlineKey = [&](std::size_t i) {
    return tasks[i].deadlineNs > 0 ? tasks[i].deadlineNs : std::numeric_limits<std::int64_t>::max();
  };
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    if (tasks[a].priority != tasks[b].priority) {
      return tasks[a].priority > tasks[b].priority;
    }
    if (deadlineKey(a) != deadlineKey(b)) {
      return deadlineKey(a) < deadlineKey(b);
    }
    return tasks[a].createdNs < tasks[b].createdNs;
  });
  std::vector<char> taken(robots.size(), 0);
  std::size_t free = robots.size();
  std::vector<Assignment> out;
  for (std::size_t i : order) {
    if (free == 0) {
      break;
    }
    const Task& t = tasks[i];
    const RobotTravel fromRobot = travel(t);
    double best = kInfeasible;
    double bestTravel = 0.0;
    std::size_t bestJ = 0;
    for (std::size_t j = 0; j < robots.size(); ++j) {
      if (taken[j] != 0 || !eligible(robots[j], t, p_)) {
        continue;
      }
      const double d = fromRobot(robots[j]);
      if (!std::isfinite(d)) {
        continue;
      }
      const double c = pairCost(t, d, p_, nowNs);
      if (c < best) {
        best = c;
        bestTravel = d;
        bestJ = j;
      }
    }
    if (std::isfinite(best)) {
      taken[bestJ] = 1;
      --free;
      out.push_back({i, bestJ, best, bestTravel});
    }
  }
  return out;
}

}  // namespace fleet
