// Switchable dependencies (Execution::letPass; docs/algorithms.md, "Switchable dependencies"): a
// robot waiting on a late one may go first, the late one's entries put behind its own.

#include <cstdint>
#include <limits>
#include <vector>

#include "fleet/traffic/execution.hpp"

namespace fleet::traffic {

bool Execution::letPass(std::size_t robot, std::int64_t minBehind) {
  if (robot >= routes_.size())
    return false;
  const Route& mine = routes_[robot];
  if (mine.released >= mine.last())
    return false;
  std::vector<std::size_t> late;
  for (const auto& d : mine[mine.released + 1].deps) {
    const auto progress = routes_[d.robot].progress;
    if (progress < d.index && d.index - progress >= minBehind)
      late.push_back(d.robot);
  }
  if (late.empty())
    return false;
  // Nothing is copied or derived again unless some late robot is really put behind: most calls
  // find none (the late robots' remaining routes do not meet this one's before their own end), and
  // A whole-fleet rederive() per waiting robot per update was most of the traffic manager's time at
  // 300 robots.
  // What it changes, to undo when the let-pass fails: the late robots' orders (shifts) and the
  // dependencies rederive() rewrites (those of unreleased entries on touched nodes). Copying every
  // route instead was a third of the update at 300 robots.
  struct Shift {
    std::size_t robot;
    std::int64_t from;
    std::int64_t by;
  };
  std::vector<Shift> shifts;
  std::vector<std::uint8_t> touched;  // per node: at or beside an entry whose order changed
  for (const std::size_t b : late) {
    Route& other = routes_[b];
    if (other.released >= other.last())
      continue;
    const std::int64_t horizon = other[other.last()].order;
    std::int64_t firstOther = -1;
    std::int64_t latestMine = std::numeric_limits<std::int64_t>::min();
    for (std::int64_t j = other.released + 1; j <= other.last(); ++j) {
      for (std::int64_t i = mine.released + 1; i <= mine.last(); ++i) {
        // Where this robot comes by again after the late one's route ends, no order is needed yet.
        if (mine[i].order > horizon || !graph_.conflicting(mine[i].node, other[j].node))
          continue;
        if (firstOther < 0)
          firstOther = j;
        latestMine = std::max(latestMine, mine[i].order);
      }
    }
    if (firstOther < 0)
      continue;
    const std::int64_t shift = latestMine + 1 - other[firstOther].order;
    if (shift <= 0)
      continue;
    if (shifts.empty())
      touched.assign(graph_.size(), 0);
    shifts.push_back(Shift{b, firstOther, shift});
    for (std::int64_t j = firstOther; j <= other.last(); ++j) {
      Entry& e = other.entries[static_cast<std::size_t>(j - other.first)];
      e.order += shift;
      touched[static_cast<std::size_t>(e.node)] = 1;
      for (NodeId x : graph_.conflicts(e.node))
        touched[static_cast<std::size_t>(x)] = 1;
    }
  }
  if (shifts.empty())
    return false;
  struct SavedDeps {
    std::size_t robot;
    std::size_t entry;
    std::vector<Dependency> deps;
  };
  std::vector<SavedDeps> savedDeps;
  for (std::size_t r = 0; r < routes_.size(); ++r) {
    Route& route = routes_[r];
    for (std::int64_t i = route.released + 1; i <= route.last(); ++i) {
      const auto k = static_cast<std::size_t>(i - route.first);
      if (touched[static_cast<std::size_t>(route.entries[k].node)] != 0)
        savedDeps.push_back(SavedDeps{r, k, route.entries[k].deps});
    }
  }
  if (!rederive(&touched) || !satisfied(routes_[robot][routes_[robot].released + 1])) {
    for (auto& d : savedDeps)
      routes_[d.robot].entries[d.entry].deps = std::move(d.deps);
    for (const Shift& sh : shifts) {
      Route& other = routes_[sh.robot];
      for (std::int64_t j = sh.from; j <= other.last(); ++j)
        other.entries[static_cast<std::size_t>(j - other.first)].order -= sh.by;
    }
    return false;
  }
  rebuildVisitors();
  return true;
}

}  // namespace fleet::traffic
