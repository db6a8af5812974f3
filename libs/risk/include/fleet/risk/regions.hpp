#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "fleet/core/vec2.hpp"
#include "fleet/risk/iso_levels.hpp"

namespace fleet::risk {

/// Closed ring of map-frame vertices (first vertex not repeated), only at corners.
using Ring = std::vector<Vec2>;

/// One connected (4-neighbour) set of cells of one iso-level: outer boundary counter-clockwise, holes
/// clockwise, along cell edges. Rings may touch at a vertex where cells touch diagonally.
struct Region {
  int level = 0;
  Ring outer;
  std::vector<Ring> holes;
  std::size_t cells = 0;
};

/// Every connected region of every level >= minLevel (level 0, "no risk", is skipped by default),
/// ordered by level then by the row-major index of the region's first cell. Boundary tracing on the
/// cell edges (marching squares on the level-indicator, with saddles resolved for 4-connectivity).
std::vector<Region> extractRegions(const LevelGrid& grid, int minLevel = 1);

/// extractRegions with its working buffers (labels and traced sides: 5 bytes per cell) kept between
/// calls, for callers that extract every cycle.
class RegionExtractor {
 public:
  std::vector<Region> extract(const LevelGrid& grid, int minLevel = 1);

 private:
  struct CellRef {
    std::uint32_t cell, i, j;
  };
  struct SideRef {
    std::uint32_t cell, side;
  };
  std::vector<std::int32_t> label_;
  std::vector<std::uint8_t> traced_;
  std::vector<CellRef> stack_;
  std::vector<SideRef> edges_;
  Ring ring_;
  std::vector<Region> regions_;  // in discovery order, before ordering by level
};

/// Signed area of a ring (positive when counter-clockwise).
double signedArea(const Ring& ring);

/// Even-odd point-in-region test (inside the outer ring and not inside a hole).
bool regionContains(const Region& region, Vec2 point);

}  // namespace fleet::risk
