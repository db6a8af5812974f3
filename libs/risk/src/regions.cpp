#include "fleet/risk/regions.hpp"

#include <algorithm>
#include <cstdint>

namespace fleet::risk {
namespace {

// Directions of boundary edges: +x, +y, −x, −y. A left turn is (d + 1) % 4.
constexpr int kDx[4] = {1, 0, -1, 0};
constexpr int kDy[4] = {0, 1, 0, -1};

struct Edge {
  std::uint32_t from;  // vertex id j·(W+1) + i
  std::uint8_t dir;
  bool used;
};

}  // namespace

double signedArea(const Ring& ring) {
  double a = 0.0;
  for (std::size_t k = 0; k < ring.size(); ++k) {
    const Vec2& p = ring[k];
    const Vec2& q = ring[(k + 1) % ring.size()];
    a += p.cross(q);
  }
  return 0.5 * a;
}

namespace {
bool ringContains(const Ring& ring, Vec2 pt) {
  bool in = false;
  for (std::size_t k = 0, m = ring.size() - 1; k < ring.size(); m = k++) {
    const Vec2& a = ring[k];
    const Vec2& b = ring[m];
    if ((a.y > pt.y) != (b.y > pt.y) && pt.x < (b.x - a.x) * (pt.y - a.y) / (b.y - a.y) + a.x) {
      in = !in;
    }
  }
  return in;
}
}  // namespace

bool regionContains(const Region& region, Vec2 point) {
  if (region.outer.empty() || !ringContains(region.outer, point)) {
    return false;
  }
  return std::none_of(region.holes.begin(), region.holes.end(),
                      [&](const Ring& h) { return ringContains(h, point); });
}

std::vector<Region> extractRegions(const LevelGrid& grid, int minLevel) {
  RegionExtractor extractor;
  return extractor.extract(grid, minLevel);
}

std::vector<Region> RegionExtractor::extract(const LevelGrid& grid, int minLevel) {
  const GridSpec& g = grid.spec;
  const int W = g.width;
  const int H = g.height;
  std::vector<Region> regions;
  if (W <= 0 || H <= 0 || grid.level.size() != g.cellCount()) {
    return regions;
  }
  const std::uint32_t VW = static_cast<std::uint32_t>(W) + 1;
  label_.assign(g.cellCount(), -1);
  // Outgoing boundary edges per vertex (at most two, at a saddle), reset after each component.
  const std::size_t vertices = static_cast<std::size_t>(VW) * static_cast<std::size_t>(H + 1);
  if (out_.size() != vertices) {
    out_.assign(vertices, {-1, -1});  // both slots of a vertex share a cache line
  }
  auto& label = label_;
  auto& out = out_;
  std::vector<std::uint32_t> stack;
  std::vector<Edge> edges;

  for (std::size_t seed = 0; seed < grid.level.size(); ++seed) {
    const int lvl = grid.level[seed];
    if (lvl < minLevel || label[seed] >= 0) {
      continue;
    }
    const auto id = static_cast<std::int32_t>(regions.size());
    // Flood fill (4-neighbour) of the component, emitting its boundary edges on the way: a 4-neighbour
    // of the same level is in the same component, anything else (other level, off the grid) is across
    // the boundary. Edges keep the component on their left.
    edges.clear();
    auto vid = [&](int i, int j) {
      return static_cast<std::uint32_t>(j) * VW + static_cast<std::uint32_t>(i);
    };
    auto addEdge = [&](std::uint32_t from, std::uint8_t dir) {
      const auto e = static_cast<std::int32_t>(edges.size());
      edges.push_back(Edge{from, dir, false});
      (out[from][0] < 0 ? out[from][0] : out[from][1]) = e;
    };
    std::size_t cells = 0;
    stack.assign(1, static_cast<std::uint32_t>(seed));
    label[seed] = id;
    while (!stack.empty()) {
      const std::uint32_t c = stack.back();
      stack.pop_back();
      ++cells;
      const int i = static_cast<int>(c % static_cast<std::uint32_t>(W));
      const int j = static_cast<int>(c / static_cast<std::uint32_t>(W));
      // Neighbours: below (edge +x at the bottom), right (+y), above (−x), left (−y).
      const int ni[4] = {i, i + 1, i, i - 1};
      const int nj[4] = {j - 1, j, j + 1, j};
      const std::uint32_t from[4] = {vid(i, j), vid(i + 1, j), vid(i + 1, j + 1), vid(i, j + 1)};
      for (int n = 0; n < 4; ++n) {
        const bool inGrid = ni[n] >= 0 && nj[n] >= 0 && ni[n] < W && nj[n] < H;
        const std::size_t nc = inGrid ? g.index(ni[n], nj[n]) : 0;
        if (!inGrid || grid.level[nc] != lvl) {
          addEdge(from[n], static_cast<std::uint8_t>(n));
        } else if (label[nc] < 0) {
          label[nc] = id;
          stack.push_back(static_cast<std::uint32_t>(nc));
        }
      }
    }
    Region region;
    region.level = lvl;
    region.cells = cells;
    for (std::size_t start = 0; start < edges.size(); ++start) {
      if (edges[start].used) {
        continue;
      }
      Ring ring;
      std::size_t e = start;
      int prevDir = -1;
      while (!edges[e].used) {
        edges[e].used = true;
        const int dir = edges[e].dir;
        const std::uint32_t from = edges[e].from;
        if (dir != prevDir) {  // keep corners only
          ring.push_back(Vec2{g.originX + static_cast<double>(from % VW) * g.resolution,
                              g.originY + static_cast<double>(from / VW) * g.resolution});
        }
        prevDir = dir;
        const std::uint32_t to = from + static_cast<std::uint32_t>(kDx[dir]) +
                                 static_cast<std::uint32_t>(kDy[dir]) * VW;  // unsigned wrap is intended
        const std::int32_t a = out[to][0];
        const std::int32_t b = out[to][1];
        std::int32_t next = a;
        if (b >= 0) {
          // Saddle: turn left, hugging the current cell, so diagonal neighbours stay apart.
          next = edges[static_cast<std::size_t>(a)].dir == (dir + 1) % 4 ? a : b;
          if (edges[static_cast<std::size_t>(next)].used) {
            next = next == a ? b : a;
          }
        }
        if (next < 0) {
          break;
        }
        e = static_cast<std::size_t>(next);
      }
      // The start vertex is a corner unless the ring closed going straight through it.
      if (ring.size() > 1 && edges[start].dir == prevDir) {
        ring.erase(ring.begin());
      }
      if (signedArea(ring) > 0.0) {
        region.outer = std::move(ring);
      } else {
        region.holes.push_back(std::move(ring));
      }
    }
    for (const auto& e : edges) {
      out[e.from] = {-1, -1};
    }
    regions.push_back(std::move(region));
  }
  // Order by level, stable in first-cell order (a counting pass instead of sorting heavy objects).
  std::vector<std::size_t> start(static_cast<std::size_t>(kMaxLevels) + 2, 0);
  for (const auto& r : regions) {
    ++start[static_cast<std::size_t>(r.level) + 1];
  }
  for (std::size_t l = 1; l < start.size(); ++l) {
    start[l] += start[l - 1];
  }
  std::vector<Region> ordered(regions.size());
  for (auto& r : regions) {
    ordered[start[static_cast<std::size_t>(r.level)]++] = std::move(r);
  }
  return ordered;
}

}  // namespace fleet::risk
