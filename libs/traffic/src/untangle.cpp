#include "fleet/traffic/untangle.hpp"

#include <algorithm>
#include <array>
#include <stdexcept>
#include <string>
#include <unordered_map>

namespace fleet::traffic {

namespace {

using Config = std::array<NodeId, kMaxUntangleGroup>;

struct ConfigHash {
  std::size_t operator()(const Config& c) const {
    std::uint64_t h = 0x9e3779b97f4a7c15ULL;
    for (const NodeId v : c) {
      h ^= static_cast<std::uint64_t>(static_cast<std::uint32_t>(v)) + 0x9e3779b97f4a7c15ULL + (h << 6) +
           (h >> 2);
    }
    return static_cast<std::size_t>(h);
  }
};

}  // namespace

std::optional<UntangleResult> untangle(const Graph& graph, const UntangleProblem& p) {
  const std::size_t k = p.starts.size();
  if (k > kMaxUntangleGroup || p.tables.size() != k || p.counts.size() != k) {
    throw std::invalid_argument("untangle: " + std::to_string(k) + " members (at most " +
                                std::to_string(kMaxUntangleGroup) + "), " + std::to_string(p.tables.size()) +
                                " tables, " + std::to_string(p.counts.size()) + " flags");
  }
  Config start{};
  start.fill(kNoNode);
  for (std::size_t i = 0; i < k; ++i)
    start[i] = p.starts[i];
  // Whether the member moving into v would be too close to another member.
  const auto clearOfMembers = [&](const Config& c, std::size_t mover, NodeId v) {
    for (std::size_t j = 0; j < k; ++j) {
      if (j != mover && (c[j] == v || graph.conflicting(c[j], v)))
        return false;
    }
    return true;
  };
  const auto closer = [&](const Config& c) -> std::optional<std::size_t> {
    for (std::size_t i = 0; i < k; ++i) {
      const float* t = p.tables[i];
      if (p.counts[i] != 0 && t != nullptr &&
          t[static_cast<std::size_t>(c[i])] < t[static_cast<std::size_t>(start[i])])
        return i;
    }
    return std::nullopt;
  };
  // Clearance from the others depends on the node alone: remembered per node.
  std::unordered_map<NodeId, bool> clearCache;
  const auto clearOfOthers = [&](NodeId v) {
    const auto [it, inserted] = clearCache.try_emplace(v, false);
    if (inserted)
      it->second = p.clearOfOthers(v);
    return it->second;
  };

  struct Item {
    Config config;
    std::int32_t parent;
    int depth;
  };
  std::vector<Item> items{{start, -1, 0}};
  std::unordered_map<Config, std::int32_t, ConfigHash> seen{{start, 0}};
  std::optional<std::pair<std::int32_t, std::size_t>> found;
  for (std::size_t head = 0; head < items.size() && !found; ++head) {
    if (items[head].depth >= p.maxSteps)
      continue;
    for (std::size_t i = 0; i < k && !found; ++i) {
      const Config c = items[head].config;
      for (const Edge& e : graph.edges(c[i])) {
        if (!e.open || !graph.isOpen(e.to) || (p.mayMove && !p.mayMove(i, c[i], e.to)) ||
            !clearOfMembers(c, i, e.to) || !clearOfOthers(e.to))
          continue;
        Config n = c;
        n[i] = e.to;
        if (seen.contains(n))
          continue;
        if (items.size() >= p.maxConfigurations)
          return std::nullopt;
        const auto id = static_cast<std::int32_t>(items.size());
        seen.emplace(n, id);
        items.push_back({n, static_cast<std::int32_t>(head), items[head].depth + 1});
        if (const auto m = closer(n)) {
          found = std::pair{id, *m};
          break;
        }
      }
    }
  }
  if (!found)
    return std::nullopt;
  UntangleResult r;
  r.improved = found->second;
  for (std::int32_t at = found->first; at >= 0; at = items[static_cast<std::size_t>(at)].parent) {
    const Config& c = items[static_cast<std::size_t>(at)].config;
    r.steps.emplace_back(c.begin(), c.begin() + static_cast<std::ptrdiff_t>(k));
  }
  std::reverse(r.steps.begin(), r.steps.end());
  return r;
}

}  // namespace fleet::traffic
