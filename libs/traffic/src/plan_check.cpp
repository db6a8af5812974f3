#include "fleet/traffic/plan_check.hpp"

#include <algorithm>

namespace fleet::traffic {

namespace {

std::size_t at(NodeId v) {
  return static_cast<std::size_t>(v);
}

// Deliberately plain: pairwise questions answered from the graph's own lookups, no planner state.
class Checker {
 public:
  Checker(const Graph& g, const PlanCheckOptions& o) : g_(g), o_(o), occupant_(g.size(), kNone) {}

  bool full() const { return out_.size() >= o_.maxViolations; }

  void add(ViolationKind k, std::size_t step, std::vector<std::size_t> agents, std::vector<NodeId> nodes) {
    if (!full()) {
      out_.push_back(Violation{k, step, std::move(agents), std::move(nodes)});
    }
  }

  /// Every agent on a valid node and no two on conflicting nodes. false when a node is invalid (the
  /// moves into and out of this configuration are then not checked).
  bool configuration(std::size_t t, const std::vector<NodeId>& c) {
    bool valid = true;
    for (std::size_t i = 0; i < c.size(); ++i) {
      if (!g_.valid(c[i])) {
        add(ViolationKind::kBadNode, t, {i}, {c[i]});
        valid = false;
      }
    }
    if (!valid) {
      return false;
    }
    for (std::size_t i = 0; i < c.size() && !full(); ++i) {
      const auto report = [&](NodeId w) {
        const std::size_t j = occupant_[at(w)];
        if (j != kNone) {
          add(ViolationKind::kVertex, t, {j, i}, {c[j], c[i]});
        }
      };
      report(c[i]);
      for (const NodeId w : g_.conflicts(c[i])) {
        report(w);
      }
      if (occupant_[at(c[i])] == kNone) {
        occupant_[at(c[i])] = i;
      }
    }
    for (const NodeId v : c) {
      occupant_[at(v)] = kNone;
    }
    return true;
  }

  void moves(std::size_t t, const std::vector<NodeId>& a, const std::vector<NodeId>& b) {
    for (std::size_t i = 0; i < a.size() && !full(); ++i) {
      if (a[i] != b[i] && g_.edge(a[i], b[i]) == nullptr) {
        add(ViolationKind::kNoEdge, t, {i}, {a[i], b[i]});
      }
    }
    // Swaps: i moves into what j excludes now and j into what i excludes now, both moving.
    for (std::size_t i = 0; i < a.size(); ++i) {
      occupant_[at(a[i])] = i;
    }
    for (std::size_t i = 0; i < a.size() && !full(); ++i) {
      if (a[i] == b[i]) {
        continue;
      }
      const auto check = [&](NodeId w) {
        const std::size_t j = occupant_[at(w)];
        if (j == kNone || j <= i || a[j] == b[j]) {
          return;
        }
        if (g_.conflicting(b[j], a[i])) {
          add(ViolationKind::kSwap, t, {i, j}, {a[i], b[i], a[j], b[j]});
        }
      };
      check(b[i]);
      for (const NodeId w : g_.conflicts(b[i])) {
        check(w);
      }
    }
    if (o_.rotations) {
      rotations(t, a, b);
    }
    for (const NodeId v : a) {
      occupant_[at(v)] = kNone;
    }
  }

 private:
  static constexpr std::size_t kNone = static_cast<std::size_t>(-1);

  /// Cycles of "i follows j" (i moves into what j excludes now, j moves): a colouring depth-first
  /// search (white, on the path, done). `occupant_` holds configuration a.
  void rotations(std::size_t t, const std::vector<NodeId>& a, const std::vector<NodeId>& b) {
    const std::size_t n = a.size();
    colour_.assign(n, 0);
    const auto followed = [&](std::size_t i) {
      std::vector<std::size_t> out;
      if (a[i] == b[i]) {
        return out;
      }
      const auto take = [&](NodeId w) {
        const std::size_t j = occupant_[at(w)];
        if (j != kNone && j != i && a[j] != b[j]) {
          out.push_back(j);
        }
      };
      take(b[i]);
      for (const NodeId w : g_.conflicts(b[i])) {
        take(w);
      }
      return out;
    };
    for (std::size_t s = 0; s < n && !full(); ++s) {
      if (colour_[s] != 0) {
        continue;
      }
      std::vector<std::pair<std::size_t, std::vector<std::size_t>>> path;
      path.emplace_back(s, followed(s));
      colour_[s] = 1;
      while (!path.empty() && !full()) {
        auto& [v, next] = path.back();
        if (next.empty()) {
          colour_[v] = 2;
          path.pop_back();
          continue;
        }
        const std::size_t w = next.back();
        next.pop_back();
        if (colour_[w] == 1) {
          // Two agents following each other are a swap, already reported as one.
          if (path.size() >= 2 && path[path.size() - 2].first == w) {
            continue;
          }
          std::vector<std::size_t> cycle;
          std::vector<NodeId> nodes;
          auto it = std::find_if(path.begin(), path.end(), [&](const auto& f) { return f.first == w; });
          for (; it != path.end(); ++it) {
            cycle.push_back(it->first);
            nodes.push_back(a[it->first]);
          }
          add(ViolationKind::kRotation, t, std::move(cycle), std::move(nodes));
        } else if (colour_[w] == 0) {
          colour_[w] = 1;
          path.emplace_back(w, followed(w));
        }
      }
    }
  }

  const Graph& g_;
  const PlanCheckOptions& o_;
  std::vector<std::size_t> occupant_;
  std::vector<std::uint8_t> colour_;

 public:
  std::vector<Violation> out_;
};

}  // namespace

std::vector<Violation> checkPlan(const Graph& graph, std::span<const std::vector<NodeId>> configs,
                                 const PlanCheckOptions& options) {
  Checker c(graph, options);
  bool previousValid = false;
  for (std::size_t t = 0; t < configs.size() && !c.full(); ++t) {
    if (t > 0 && configs[t].size() != configs[0].size()) {
      c.add(ViolationKind::kAgentCount, t, {}, {});
      previousValid = false;
      continue;
    }
    const bool valid = c.configuration(t, configs[t]);
    if (valid && previousValid) {
      c.moves(t, configs[t - 1], configs[t]);
    }
    previousValid = valid;
  }
  return std::move(c.out_);
}

const char* toString(ViolationKind kind) {
  switch (kind) {
    case ViolationKind::kBadNode:
      return "invalid node";
    case ViolationKind::kNoEdge:
      return "move without an edge";
    case ViolationKind::kVertex:
      return "vertex conflict";
    case ViolationKind::kSwap:
      return "swap";
    case ViolationKind::kRotation:
      return "rotation";
    case ViolationKind::kAgentCount:
      return "wrong number of agents";
  }
  return "?";
}

std::string describe(const Violation& v) {
  std::string s = "step " + std::to_string(v.step) + ": " + toString(v.kind);
  if (!v.agents.empty()) {
    s += ", agents";
    for (const auto a : v.agents) {
      s += " " + std::to_string(a);
    }
  }
  if (!v.nodes.empty()) {
    s += ", nodes";
    for (const auto n : v.nodes) {
      s += " " + std::to_string(n);
    }
  }
  return s;
}

}  // namespace fleet::traffic
