#pragma once

#include <optional>

#include "fleet/core/expected.hpp"
#include "fleet/core/vec2.hpp"
#include "fleet/risk/iso_levels.hpp"

namespace fleet::risk {

/// A cell chosen by a query, with its value.
struct CellRisk {
  int i = 0;
  int j = 0;
  Vec2 centre;
  double risk = 0.0;  // probability (ProbabilityGrid) or level (LevelGrid)
};

/// Value of the cell holding the point; error "off_grid" outside the map.
Expected<CellRisk> riskAt(const ProbabilityGrid& grid, Vec2 point);
Expected<CellRisk> riskAt(const LevelGrid& grid, Vec2 point);

/// Largest value over every cell the segment a→b passes through (exact grid traversal, Amanatides &
/// Woo), and where. Parts of the segment off the map are ignored; nothing when none is on it.
std::optional<CellRisk> maxRiskAlongSegment(const ProbabilityGrid& grid, Vec2 a, Vec2 b);
std::optional<CellRisk> maxRiskAlongSegment(const LevelGrid& grid, Vec2 a, Vec2 b);

/// Lowest-value cell whose centre lies in the square window |x − cx| <= halfWidth, |y − cy| <=
/// halfWidth; ties go to the cell nearest the window centre (then the lowest row-major index) — the
/// "next point of motion in the lowest-risk region" of §3.2.3. Nothing when the window misses the map.
std::optional<CellRisk> lowestRiskCell(const ProbabilityGrid& grid, Vec2 centre, double halfWidth);
std::optional<CellRisk> lowestRiskCell(const LevelGrid& grid, Vec2 centre, double halfWidth);

}  // namespace fleet::risk
