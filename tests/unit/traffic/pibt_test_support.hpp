#pragma once

// Helpers of the lifelong planner's tests: small maps, random maps and a lifelong driver that keeps
// the whole plan for plan_check.

#include <gtest/gtest.h>

#include <cstdint>
#include <numeric>
#include <queue>
#include <random>
#include <string>
#include <vector>

#include "fleet/traffic/grid_map.hpp"
#include "fleet/traffic/pibt.hpp"
#include "fleet/traffic/plan_check.hpp"

namespace fleet::traffic::test {

/// Rows of a MovingAI map ('.' free, '@' blocked) as a GridMap; fails the test on a bad map.
inline GridMap gridOf(const std::vector<std::string>& rows) {
  std::string text = "type octile\nheight " + std::to_string(rows.size()) + "\nwidth " +
                     std::to_string(rows.empty() ? 0 : rows[0].size()) + "\nmap\n";
  for (const auto& r : rows) {
    text += r + "\n";
  }
  auto m = parseGridMap(text, "<test>");
  EXPECT_TRUE(m.has_value()) << (m ? "" : m.error().message);
  return m ? std::move(*m) : GridMap{};
}

/// n nodes in rows of `perRow` (1 m apart) and 3n random directed edges: every edge 1 s
/// (`unit`) or a random multiple of 0.25 s, so that shortest ways tie and sums stay exact.
inline Graph randomDigraph(int n, int perRow, bool unit, std::mt19937_64& rng) {
  Graph g;
  for (int i = 0; i < n; ++i) {
    g.addNode({static_cast<double>(i % perRow), static_cast<double>(i / perRow)});
  }
  std::uniform_int_distribution<int> node(0, n - 1);
  std::uniform_int_distribution<int> quarter(1, 8);
  for (int e = 0; e < n * 3; ++e) {
    const int a = node(rng);
    const int b = node(rng);
    if (a != b) {
      g.addEdge(a, b, unit ? 1.0 : 0.25 * quarter(rng));
    }
  }
  return g;
}

/// A random w x h map with about `density` of its cells blocked, cut down to its largest connected
/// part (every goal reachable from every start).
inline GridMap randomMap(int w, int h, double density, std::mt19937_64& rng) {
  std::bernoulli_distribution blocked(density);
  std::vector<std::string> rows(static_cast<std::size_t>(h), std::string(static_cast<std::size_t>(w), '.'));
  for (auto& r : rows) {
    for (auto& ch : r) {
      ch = blocked(rng) ? '@' : '.';
    }
  }
  const GridMap first = gridOf(rows);
  std::vector<int> comp(first.freeCells(), -1);
  int best = -1;
  std::size_t bestSize = 0;
  for (std::size_t s = 0; s < comp.size(); ++s) {
    if (comp[s] >= 0) {
      continue;
    }
    const int id = static_cast<int>(s);
    std::size_t size = 0;
    std::queue<NodeId> q;
    q.push(static_cast<NodeId>(s));
    comp[s] = id;
    while (!q.empty()) {
      const NodeId v = q.front();
      q.pop();
      ++size;
      for (const Edge& e : first.graph.edges(v)) {
        if (comp[static_cast<std::size_t>(e.to)] < 0) {
          comp[static_cast<std::size_t>(e.to)] = id;
          q.push(e.to);
        }
      }
    }
    if (size > bestSize) {
      bestSize = size;
      best = id;
    }
  }
  for (std::size_t v = 0; v < comp.size(); ++v) {
    if (comp[v] != best) {
      const GridCell c = first.cell(static_cast<NodeId>(v));
      rows[static_cast<std::size_t>(c.y)][static_cast<std::size_t>(c.x)] = '@';
    }
  }
  return gridOf(rows);
}

/// A lone agent 0 stepped to its goal (at most `limit` steps): the positions it stood on, its start
/// first.
inline std::vector<Vec2> walkToGoal(const Graph& g, Pibt& p, int limit) {
  std::vector<Vec2> path{g.position(p.positions()[0])};
  for (int k = 0; k < limit && p.positions()[0] != p.goal(0); ++k)
    path.push_back(g.position(p.step()[0]));
  return path;
}

/// Changes of direction along a path of positions.
inline int turnsAlong(const std::vector<Vec2>& path) {
  int n = 0;
  for (std::size_t i = 2; i < path.size(); ++i) {
    const Vec2 a = path[i - 1] - path[i - 2], b = path[i] - path[i - 1];
    n += a.dot(b) < a.norm() * b.norm() - 1e-9 ? 1 : 0;
  }
  return n;
}

/// Lifelong run: `n` agents on random distinct nodes, a new random goal whenever one is reached
/// (and, with `goalChurn`, at random for that share of agents every step). Keeps every configuration.
struct LifelongRun {
  std::vector<std::vector<NodeId>> configs;
  std::vector<int> reached;  ///< goals reached per agent
  PibtStats stats;
};

inline LifelongRun runLifelong(const Graph& g, std::size_t n, int steps, std::uint64_t seed, PibtOptions o,
                               double goalChurn = 0.0) {
  std::mt19937_64 rng(seed);
  std::vector<NodeId> nodes(g.size());
  std::iota(nodes.begin(), nodes.end(), 0);
  std::shuffle(nodes.begin(), nodes.end(), rng);
  // On a graph with conflict sets, starts must not exclude each other.
  std::vector<NodeId> starts;
  for (const NodeId v : nodes) {
    bool clash = false;
    for (const NodeId s : starts) {
      clash = clash || g.conflicting(s, v);
    }
    if (!clash) {
      starts.push_back(v);
    }
    if (starts.size() == n) {
      break;
    }
  }
  EXPECT_EQ(starts.size(), n) << "not enough room for the agents";
  o.seed = seed;
  Pibt p(g, starts, o);
  std::uniform_int_distribution<std::size_t> any(0, g.size() - 1);
  std::bernoulli_distribution churn(goalChurn);
  const auto newGoal = [&](std::size_t i) {
    NodeId goal = p.positions()[i];
    while (goal == p.positions()[i]) {
      goal = static_cast<NodeId>(any(rng));
    }
    p.setGoal(i, goal);
  };
  for (std::size_t i = 0; i < starts.size(); ++i) {
    newGoal(i);
  }
  LifelongRun run;
  run.reached.assign(starts.size(), 0);
  run.configs.push_back(starts);
  for (int t = 0; t < steps; ++t) {
    const auto& next = p.step();
    run.configs.push_back(next);
    for (std::size_t i = 0; i < next.size(); ++i) {
      if (next[i] == p.goal(i)) {
        ++run.reached[i];
        newGoal(i);
      } else if (goalChurn > 0.0 && churn(rng)) {
        newGoal(i);
      }
    }
  }
  run.stats = p.stats();
  return run;
}

inline std::string firstViolations(const std::vector<Violation>& v) {
  std::string s;
  for (const auto& x : v) {
    s += describe(x) + "\n";
  }
  return s;
}

}  // namespace fleet::traffic::test
