#include "traffic_bench.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <numeric>
#include <vector>

#include "fleet/planning/map_io.hpp"
#include "fleet/planning/movingai_scen.hpp"
#include "fleet/traffic/grid_map.hpp"
#include "fleet/traffic/pibt.hpp"

namespace fleet::ctl {

namespace {

using traffic::kNoNode;
using traffic::NodeId;
using Clock = std::chrono::steady_clock;

int bad(const std::string& what) {
  std::cerr << "fleetctl traffic-bench: " << what << "\n";
  return 2;
}

/// splitmix64 with an unbiased bounded draw: the same instance on every platform for a seed.
class Random {
 public:
  explicit Random(std::uint64_t seed) : s_(seed) {}
  std::uint64_t next() {
    std::uint64_t z = (s_ += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
  }
  std::size_t below(std::size_t n) {
    const std::uint64_t limit = UINT64_MAX - UINT64_MAX % n;
    std::uint64_t x = next();
    while (x >= limit) {
      x = next();
    }
    return static_cast<std::size_t>(x % n);
  }
  double unit() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }
  template <class T>
  void shuffle(std::vector<T>& v) {
    for (std::size_t i = v.size(); i > 1; --i) {
      std::swap(v[i - 1], v[below(i)]);
    }
  }

 private:
  std::uint64_t s_;
};

struct GoalEvent {
  int step;
  std::size_t agent;
  NodeId goal;
};

struct Recording {
  std::vector<std::vector<NodeId>> configs;
  std::vector<GoalEvent> goals;
};

double percentile(std::vector<double> v, double q) {
  if (v.empty()) {
    return 0.0;
  }
  std::sort(v.begin(), v.end());
  const auto rank = static_cast<std::size_t>(std::ceil(q * static_cast<double>(v.size())));
  return v[std::min(v.size() - 1, rank == 0 ? 0 : rank - 1)];
}

traffic::Rotations rotationsOf(const std::string& s) {
  if (s == "allow") {
    return traffic::Rotations::kAllow;
  }
  if (s == "cancel") {
    return traffic::Rotations::kCancel;
  }
  return traffic::Rotations::kAvoid;
}

bool writePlan(const std::string& path, const traffic::GridMap& map, const TrafficBenchOptions& o,
               const Recording& rec, std::size_t goalsReached) {
  std::ofstream out(path, std::ios::binary);
  if (!out) {
    return false;
  }
  const auto cell = [&](NodeId v) {
    const auto c = map.cell(v);
    return "[" + std::to_string(c.x) + "," + std::to_string(c.y) + "]";
  };
  out << "{\"format\":\"fleet-plan/1\",\"map\":\"" << map.source << "\",\"width\":" << map.width
      << ",\"height\":" << map.height << ",\"agents\":" << (rec.configs.empty() ? 0 : rec.configs[0].size())
      << ",\"steps\":" << (rec.configs.empty() ? 0 : rec.configs.size() - 1) << ",\"seed\":" << o.seed
      << ",\"mode\":\"" << (o.mapd ? "mapd" : "lifelong") << "\",\"rotations\":\"" << o.rotations
      << "\",\"goals_reached\":" << goalsReached << ",\n\"plan\":[\n";
  for (std::size_t t = 0; t < rec.configs.size(); ++t) {
    out << "[";
    for (std::size_t i = 0; i < rec.configs[t].size(); ++i) {
      if (i > 0) {
        out << ',';
      }
      out << cell(rec.configs[t][i]);
    }
    out << (t + 1 < rec.configs.size() ? "],\n" : "]\n");
  }
  // A goal holds for its agent from `step` on (until the agent's next event); kNoNode is null.
  out << "],\n\"goals\":[\n";
  for (std::size_t k = 0; k < rec.goals.size(); ++k) {
    const auto& g = rec.goals[k];
    out << "[" << g.step << "," << g.agent << ",";
    out << (g.goal == kNoNode ? std::string("null") : cell(g.goal));
    out << (k + 1 < rec.goals.size() ? "],\n" : "]\n");
  }
  out << "]}\n";
  return static_cast<bool>(out);
}

void printTimes(const std::vector<double>& ms) {
  const double sum = std::accumulate(ms.begin(), ms.end(), 0.0);
  std::printf("step_ms_p50=%.3f\nstep_ms_p99=%.3f\nstep_ms_max=%.3f\nstep_ms_mean=%.3f\n",
              percentile(ms, 0.50), percentile(ms, 0.99),
              ms.empty() ? 0.0 : *std::max_element(ms.begin(), ms.end()),
              ms.empty() ? 0.0 : sum / static_cast<double>(ms.size()));
}

void printPlannerStats(const traffic::Pibt& p) {
  std::printf("escalations=%llu\nescalation_requeues=%llu\nrotation_stops=%llu\ndistance_tables=%llu\n",
              static_cast<unsigned long long>(p.stats().escalations),
              static_cast<unsigned long long>(p.stats().escalationRequeues),
              static_cast<unsigned long long>(p.stats().rotationStops),
              static_cast<unsigned long long>(p.distances().computed()));
}

/// Agent i starts and first heads where the i-th usable row of the .scen says (the MAPF benchmark's
/// convention); a row whose start another agent already has is passed over, as is every row the
/// reader skips. Both are counted on stderr by reason, and too few rows is bad input.
struct ScenAgents {
  std::vector<NodeId> starts;
  std::vector<NodeId> goals;
};
Expected<ScenAgents> scenAgents(const traffic::GridMap& map, const TrafficBenchOptions& o) {
  auto grid = planning::loadMovingAiMap(o.map);
  if (!grid) {
    return unexpected(grid.error().code, grid.error().message);
  }
  auto scen = planning::loadMovingAiScen(o.scen, &*grid, o.map);
  if (!scen) {
    return unexpected(scen.error().code, scen.error().message);
  }
  auto skipped = scen->skippedBy();
  ScenAgents out;
  std::vector<bool> taken(map.freeCells(), false);
  for (const auto& e : scen->entries) {
    if (out.starts.size() == static_cast<std::size_t>(o.agents)) {
      break;
    }
    const NodeId s = map.node(e.startX, e.startY);
    if (taken[static_cast<std::size_t>(s)]) {
      ++skipped["duplicate_start"];
      continue;
    }
    taken[static_cast<std::size_t>(s)] = true;
    out.starts.push_back(s);
    out.goals.push_back(map.node(e.goalX, e.goalY));
  }
  for (const auto& [reason, count] : skipped) {
    std::cerr << "fleetctl traffic-bench: " << o.scen << ": " << count << " row(s) skipped: " << reason
              << "\n";
  }
  if (out.starts.size() < static_cast<std::size_t>(o.agents)) {
    return unexpected("scen_rows", o.scen + ": " + std::to_string(out.starts.size()) +
                                       " usable rows with distinct starts, " + std::to_string(o.agents) +
                                       " agents asked for");
  }
  return out;
}

int lifelong(const traffic::GridMap& map, const TrafficBenchOptions& o) {
  Random rng(o.seed);
  const auto n = static_cast<std::size_t>(o.agents);
  std::vector<NodeId> starts;
  std::vector<NodeId> firstGoals;
  if (o.scen.empty()) {
    std::vector<NodeId> cells(map.freeCells());
    std::iota(cells.begin(), cells.end(), 0);
    rng.shuffle(cells);
    starts.assign(cells.begin(), cells.begin() + static_cast<std::ptrdiff_t>(n));
  } else {
    auto agents = scenAgents(map, o);
    if (!agents) {
      return bad(agents.error().message);
    }
    starts = std::move(agents->starts);
    firstGoals = std::move(agents->goals);
  }
  traffic::PibtOptions po;
  po.seed = o.seed;
  po.rotations = rotationsOf(o.rotations);
  po.escapeAfter = o.escapeAfter;
  po.escapeProgress = o.escapeProgress;
  traffic::Pibt planner(map.graph, starts, po);
  Recording rec;
  const bool record = !o.out.empty();
  const auto newGoal = [&](std::size_t i, NodeId at, int step) {
    NodeId g = at;
    while (g == at) {
      g = static_cast<NodeId>(rng.below(map.freeCells()));
    }
    planner.setGoal(i, g);
    if (record) {
      rec.goals.push_back({step, i, g});
    }
  };
  for (std::size_t i = 0; i < n; ++i) {
    if (!firstGoals.empty() && firstGoals[i] != starts[i]) {
      planner.setGoal(i, firstGoals[i]);
      if (record) {
        rec.goals.push_back({0, i, firstGoals[i]});
      }
    } else {
      newGoal(i, starts[i], 0);
    }
  }
  if (record) {
    rec.configs.reserve(static_cast<std::size_t>(o.steps) + 1);
    rec.configs.push_back(starts);
  }
  std::vector<double> ms;
  ms.reserve(static_cast<std::size_t>(o.steps));
  std::size_t reached = 0;
  for (int t = 0; t < o.steps; ++t) {
    const auto t0 = Clock::now();
    const auto& next = planner.step();
    ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
    if (record) {
      rec.configs.push_back(next);
    }
    for (std::size_t i = 0; i < n; ++i) {
      if (next[i] == planner.goal(i)) {
        ++reached;
        newGoal(i, next[i], t + 1);
      }
    }
  }
  std::printf("mode=lifelong\nmap=%s\nwidth=%d\nheight=%d\nfree_cells=%zu\nagents=%zu\nsteps=%d\nseed=%llu\n",
              map.source.c_str(), map.width, map.height, map.freeCells(), n, o.steps,
              static_cast<unsigned long long>(o.seed));
  if (!o.scen.empty()) {
    std::printf("scen=%s\n", o.scen.c_str());
  }
  std::printf("rotations=%s\nescape_after=%d\ngoals_reached=%zu\nthroughput=%.3f\n", o.rotations.c_str(),
              o.escapeAfter, reached, static_cast<double>(reached) / o.steps);
  printTimes(ms);
  printPlannerStats(planner);
  if (record && !writePlan(o.out, map, o, rec, reached)) {
    return bad(o.out + ": cannot write the plan");
  }
  return 0;
}

struct Task {
  NodeId pickup;
  NodeId delivery;
  const float* toPickup;  ///< distance table of the pickup
  int appear;
  int finished = -1;
  int carrier = -1;  ///< agent carrying it (picked up), -1
};

int mapd(const traffic::GridMap& map, const traffic::PickupDelivery& pd, const TrafficBenchOptions& o) {
  Random rng(o.seed);
  // pibt2 starts agents on the non-task endpoints when the .pd file has any, else anywhere.
  std::vector<NodeId> pool = pd.endpoints;
  if (pool.empty()) {
    pool.resize(map.freeCells());
    std::iota(pool.begin(), pool.end(), 0);
  }
  const auto n = static_cast<std::size_t>(o.agents);
  if (n > pool.size()) {
    return bad(std::to_string(n) + " agents but only " + std::to_string(pool.size()) +
               (pd.endpoints.empty() ? " free cells" : " non-task endpoints in " + o.pd));
  }
  rng.shuffle(pool);
  std::vector<NodeId> starts(pool.begin(), pool.begin() + static_cast<std::ptrdiff_t>(n));
  traffic::PibtOptions po;
  po.seed = o.seed;
  po.rotations = rotationsOf(o.rotations);
  po.escapeAfter = o.escapeAfter;
  po.escapeProgress = o.escapeProgress;
  traffic::Pibt planner(map.graph, starts, po);
  auto& dist = planner.distances();
  // pibt2's experiments (-d) fill a distance table before the run and leave that out of comp_time;
  // the same here: every pickup's and delivery's table first, reported apart as preprocessing.
  // Every goal is a pickup or a delivery, so with room for all of them no table is ever evicted
  // and a task can keep a pointer to its pickup's table.
  const auto pre0 = Clock::now();
  dist.reserve(pd.pickups.size() + pd.deliveries.size() + n + 1);
  for (const auto* list : {&pd.pickups, &pd.deliveries}) {
    for (const NodeId v : *list) {
      (void)dist.to(v);
    }
  }
  const double preMs = std::chrono::duration<double, std::milli>(Clock::now() - pre0).count();

  std::vector<Task> tasks;
  std::vector<std::size_t> open;  // tasks not yet finished
  std::vector<int> carrying(n, -1);
  std::vector<int> target(n, -1);
  int now = 0;
  // pibt2's MAPD_Instance::update(): floor(f) tasks per step, or one with probability f below 1.
  const auto create = [&](int appear) {
    if (static_cast<int>(tasks.size()) >= o.tasks) {
      return;
    }
    int k = static_cast<int>(o.frequency);
    if (o.frequency < 1.0 && rng.unit() < o.frequency) {
      k = 1;
    }
    k = std::min(k, o.tasks - static_cast<int>(tasks.size()));
    for (int j = 0; j < k; ++j) {
      NodeId p = kNoNode;
      NodeId d = kNoNode;
      do {
        p = pd.pickups[rng.below(pd.pickups.size())];
        d = pd.deliveries[rng.below(pd.deliveries.size())];
      } while (p == d);
      open.push_back(tasks.size());
      tasks.push_back(Task{p, d, dist.to(p).data(), appear});
    }
  };
  create(0);

  Recording rec;
  const bool record = !o.out.empty();
  if (record) {
    rec.configs.push_back(starts);
  }
  std::vector<NodeId> lastGoal(n, kNoNode);
  std::vector<std::size_t> unassigned;
  std::vector<double> stepMs;
  double loopMs = 0.0;
  std::size_t finished = 0;
  bool solved = false;
  while (true) {
    const auto t0 = Clock::now();
    // Assignment: a free agent heads for the nearest pickup of a task nobody carries yet (several
    // may head for the same one: the first to get there takes it), as pibt2's PIBT_MAPD does; ties
    // go to a uniformly random one (pibt2 shuffles the list per agent; a reservoir draw on ties
    // picks from the same distribution without the shuffle), and an agent already standing on a
    // pickup takes that task at once.
    unassigned.clear();
    for (const std::size_t k : open) {
      if (tasks[k].carrier < 0) {
        unassigned.push_back(k);
      }
    }
    for (std::size_t i = 0; i < n; ++i) {
      if (carrying[i] >= 0) {
        continue;
      }
      target[i] = -1;
      const auto at = static_cast<std::size_t>(planner.positions()[i]);
      float best = traffic::DistanceTable::kUnreachable;
      std::size_t ties = 0;
      std::size_t pick = unassigned.size();
      for (std::size_t u = 0; u < unassigned.size(); ++u) {
        if (tasks[unassigned[u]].carrier >= 0) {
          continue;  // taken at its pickup by an agent earlier in this loop
        }
        const float d = tasks[unassigned[u]].toPickup[at];
        if (d < best) {
          best = d;
          ties = 1;
          pick = u;
        } else if (d == best && rng.below(++ties) == 0) {
          pick = u;
        }
      }
      if (pick == unassigned.size()) {
        continue;
      }
      const std::size_t k = unassigned[pick];
      if (best == 0.0F) {
        tasks[k].carrier = static_cast<int>(i);
        carrying[i] = static_cast<int>(k);
      } else {
        target[i] = static_cast<int>(k);
      }
    }
    for (std::size_t i = 0; i < n; ++i) {
      NodeId g = kNoNode;
      if (carrying[i] >= 0) {
        g = tasks[static_cast<std::size_t>(carrying[i])].delivery;
      } else if (target[i] >= 0) {
        g = tasks[static_cast<std::size_t>(target[i])].pickup;
      }
      planner.setGoal(i, g);
      planner.setTaskPriority(i, carrying[i] >= 0 ? 1 : 0);
      if (record && g != lastGoal[i]) {
        rec.goals.push_back({now, i, g});
      }
      lastGoal[i] = g;
    }
    const auto t1 = Clock::now();
    const auto& next = planner.step();
    const auto t2 = Clock::now();
    if (record) {
      rec.configs.push_back(next);
    }
    for (std::size_t i = 0; i < n; ++i) {
      if (carrying[i] >= 0) {
        auto& task = tasks[static_cast<std::size_t>(carrying[i])];
        if (next[i] == task.delivery) {
          task.finished = now + 1;
          ++finished;
          open.erase(std::find(open.begin(), open.end(), static_cast<std::size_t>(carrying[i])));
          carrying[i] = -1;
        }
      } else if (target[i] >= 0) {
        auto& task = tasks[static_cast<std::size_t>(target[i])];
        if (task.carrier < 0 && next[i] == task.pickup) {
          task.carrier = static_cast<int>(i);
          carrying[i] = target[i];
        }
        target[i] = -1;
      }
    }
    create(now + 1);
    ++now;
    const auto t3 = Clock::now();
    stepMs.push_back(std::chrono::duration<double, std::milli>(t2 - t1).count());
    loopMs += std::chrono::duration<double, std::milli>(t3 - t0).count();
    if (static_cast<int>(finished) == o.tasks) {
      solved = true;
      break;
    }
    if (now >= o.maxSteps) {
      break;
    }
  }
  double service = 0.0;
  for (const auto& t : tasks) {
    if (t.finished >= 0) {
      service += t.finished - t.appear;
    }
  }
  std::printf("mode=mapd\nmap=%s\npd=%s\nagents=%zu\ntasks=%d\nfrequency=%g\nseed=%llu\nrotations=%s\n",
              map.source.c_str(), o.pd.c_str(), n, o.tasks, o.frequency,
              static_cast<unsigned long long>(o.seed), o.rotations.c_str());
  std::printf(
      "solved=%d\ntasks_finished=%zu\nservice_time=%.3f\nmakespan=%d\ncomp_time_ms=%.3f\n"
      "preprocessing_ms=%.3f\n",
      solved ? 1 : 0, finished, finished > 0 ? service / static_cast<double>(finished) : 0.0, now, loopMs,
      preMs);
  printTimes(stepMs);
  printPlannerStats(planner);
  if (record && !writePlan(o.out, map, o, rec, finished)) {
    return bad(o.out + ": cannot write the plan");
  }
  return solved ? 0 : 1;
}

}  // namespace

int runTrafficBench(const TrafficBenchOptions& o) {
  if (o.agents < 1) {
    return bad("--agents must be at least 1, got " + std::to_string(o.agents));
  }
  if (o.steps < 1) {
    return bad("--steps must be at least 1, got " + std::to_string(o.steps));
  }
  if (o.rotations != "avoid" && o.rotations != "cancel" && o.rotations != "allow") {
    return bad("--rotations must be avoid, cancel or allow, got '" + o.rotations + "'");
  }
  if (o.escapeAfter < 0) {
    return bad("--escape-after must be 0 or more");
  }
  auto map = traffic::loadGridMap(o.map);
  if (!map) {
    return bad(map.error().message);
  }
  if (map->freeCells() < 2) {
    return bad(o.map + ": fewer than two free cells");
  }
  if (!o.scen.empty() && o.mapd) {
    return bad("--scen is for lifelong mode; MAPD starts agents on the .pd file's endpoints");
  }
  if (!o.mapd) {
    if (static_cast<std::size_t>(o.agents) > map->freeCells()) {
      return bad(std::to_string(o.agents) + " agents but " + o.map + " has only " +
                 std::to_string(map->freeCells()) + " free cells");
    }
    return lifelong(*map, o);
  }
  if (o.pd.empty()) {
    return bad("--mapd needs --pd FILE.pd (pickup and delivery cells)");
  }
  if (o.tasks < 1) {
    return bad("--tasks must be at least 1");
  }
  if (!(o.frequency > 0.0) || !std::isfinite(o.frequency)) {
    return bad("--frequency must be positive");
  }
  if (o.maxSteps < 1) {
    return bad("--max-steps must be at least 1");
  }
  auto pd = traffic::loadPickupDelivery(o.pd, *map);
  if (!pd) {
    return bad(pd.error().message);
  }
  return mapd(*map, *pd, o);
}

}  // namespace fleet::ctl
