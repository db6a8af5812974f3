#include "fleet/risk/regions.hpp"

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <limits>

namespace fleet::risk {
namespace {

// Directions of boundary edges: +x, +y, −x, −y. A left turn is (d + 1) % 4.
constexpr int kDx[4] = {1, 0, -1, 0};
constexpr int kDy[4] = {0, 1, 0, -1};
constexpr std::int32_t kOffGrid = std::numeric_limits<std::int32_t>::min();  // neither an id nor a level key

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
  auto& regions = regions_;
  regions.clear();
  if (W <= 0 || H <= 0 || grid.level.size() != g.cellCount()) {
    return {};
  }
  const std::uint8_t* level = grid.level.data();
  // label_ holds the region id of a labelled cell and −1 − level of one not yet labelled, so the flood
  // fill settles "same level, not yet visited" with one load.
  label_.resize(g.cellCount());
  std::transform(grid.level.begin(), grid.level.end(), label_.begin(),
                 [](std::uint8_t l) { return -1 - static_cast<std::int32_t>(l); });
  // Sides of each cell already traced (bit n = side n), cleared per component from its edge list.
  if (traced_.size() != g.cellCount()) {
    traced_.assign(g.cellCount(), 0);
  }
  auto& label = label_;
  auto& traced = traced_;
  auto& stack = stack_;
  auto& edges = edges_;
  // Cell steps along the side directions +x, +y, −x, −y.
  const std::ptrdiff_t step[4] = {1, static_cast<std::ptrdiff_t>(W), -1, -static_cast<std::ptrdiff_t>(W)};

  const std::size_t cellCount = grid.level.size();
  for (std::size_t seed = 0; seed < cellCount; ++seed) {
    if (minLevel >= 1) {
      // Skip level-0 cells (most of a risk map) eight at a time.
      while (seed + 8 <= cellCount) {
        std::uint64_t word = 0;
        std::memcpy(&word, level + seed, sizeof word);
        if (word != 0) {
          break;
        }
        seed += 8;
      }
      if (seed >= cellCount) {
        break;
      }
    }
    const int lvl = level[seed];
    if (lvl < minLevel || label[seed] >= 0) {
      continue;
    }
    const auto id = static_cast<std::int32_t>(regions.size());
    const std::int32_t unvisitedKey = -1 - lvl;
    // Flood fill (4-neighbour) of the component, listing its boundary edges on the way: a 4-neighbour
    // of the same level is in the same component, anything else (other level, off the grid) is across
    // the boundary. Edge n of a cell is its side with the cell on the left when walked in direction n
    // (bottom +x, right +y, top −x, left −y).
    edges.clear();
    std::size_t cells = 0;
    const auto seedI = static_cast<std::uint32_t>(seed % static_cast<std::size_t>(W));
    const auto seedJ = static_cast<std::uint32_t>(seed / static_cast<std::size_t>(W));
    stack.assign(1, CellRef{static_cast<std::uint32_t>(seed), seedI, seedJ});
    label[seed] = id;
    while (!stack.empty()) {
      const CellRef c = stack.back();
      stack.pop_back();
      ++cells;
      const int i = static_cast<int>(c.i);
      const int j = static_cast<int>(c.j);
      const bool inGrid[4] = {j > 0, i + 1 < W, j + 1 < H, i > 0};
      const std::uint32_t ni[4] = {c.i, c.i + 1, c.i, c.i - 1};
      const std::uint32_t nj[4] = {c.j - 1, c.j, c.j + 1, c.j};
      // Neighbours across the sides: below, right, above, left.
      const std::ptrdiff_t across[4] = {-step[1], step[0], step[1], -step[0]};
      for (int n = 0; n < 4; ++n) {
        const std::size_t nc = static_cast<std::size_t>(static_cast<std::ptrdiff_t>(c.cell) + across[n]);
        const std::int32_t l = inGrid[n] ? label[nc] : kOffGrid;
        if (l == unvisitedKey) {
          label[nc] = id;
          stack.push_back(CellRef{static_cast<std::uint32_t>(nc), ni[n], nj[n]});
        } else if (l != id) {  // another level or off the grid (4-neighbours of a level connect)
          edges.push_back(SideRef{c.cell, static_cast<std::uint32_t>(n)});
        }
      }
    }
    // Is cell (i, j) on the grid and of this component's level?
    auto sameLevel = [&](int i, int j) {
      return i >= 0 && j >= 0 && i < W && j < H && level[g.index(i, j)] == lvl;
    };
    Region region;
    region.level = lvl;
    region.cells = cells;
    for (const SideRef& startEdge : edges) {
      if ((traced[startEdge.cell] >> startEdge.side) & 1U) {
        continue;
      }
      Ring& ring = ring_;
      ring.clear();
      int ci = static_cast<int>(startEdge.cell % static_cast<std::uint32_t>(W));
      int cj = static_cast<int>(startEdge.cell / static_cast<std::uint32_t>(W));
      int side = static_cast<int>(startEdge.side);
      int prevDir = -1;
      while (true) {
        std::uint8_t& bits = traced[g.index(ci, cj)];
        if ((bits >> side) & 1U) {
          break;
        }
        bits = static_cast<std::uint8_t>(bits | (1U << side));
        const int dir = side;
        if (dir != prevDir) {  // keep corners only
          // Start vertex of side n: corners (0,0), (1,0), (1,1), (0,1) of the cell.
          const int vi = ci + ((dir == 1 || dir == 2) ? 1 : 0);
          const int vj = cj + ((dir == 2 || dir == 3) ? 1 : 0);
          ring.push_back(Vec2{g.originX + static_cast<double>(vi) * g.resolution,
                              g.originY + static_cast<double>(vj) * g.resolution});
        }
        prevDir = dir;
        // At the end vertex the cell ahead (L, across the next side of this cell) and the one diagonally
        // ahead-right (R) decide the next boundary edge; the cell behind-right is outside by definition.
        const int rdir = (dir + 3) % 4;
        const int li = ci + kDx[dir];
        const int lj = cj + kDy[dir];
        const int ri = li + kDx[rdir];
        const int rj = lj + kDy[rdir];
        if (!sameLevel(li, lj)) {
          // Turn left, hugging the current cell: at a saddle this keeps diagonal neighbours apart. Should
          // that edge be traced already, the vertex's other outgoing edge (along R, if R is in this
          // component) is taken, as a vertex table of the component's edges would.
          const int left = (dir + 1) % 4;
          if (((bits >> left) & 1U) != 0 && sameLevel(ri, rj) && label[g.index(ri, rj)] == id) {
            ci = ri;
            cj = rj;
            side = rdir;
          } else {
            side = left;
          }
        } else if (sameLevel(ri, rj)) {
          ci = ri;  // turn right around the vertex, onto R
          cj = rj;
          side = rdir;
        } else {
          ci = li;  // straight on along L
          cj = lj;
        }
      }
      // The start vertex is a corner unless the ring closed going straight through it.
      const auto first =
          ring.begin() + ((ring.size() > 1 && static_cast<int>(startEdge.side) == prevDir) ? 1 : 0);
      Ring exact(first, ring.end());  // one allocation of the final size
      if (signedArea(exact) > 0.0) {
        region.outer = std::move(exact);
      } else {
        region.holes.push_back(std::move(exact));
      }
    }
    for (const SideRef& e : edges) {
      traced[e.cell] = 0;
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
  regions.clear();  // keeps its capacity: no fresh (page-faulting) allocation next time
  return ordered;
}

}  // namespace fleet::risk
