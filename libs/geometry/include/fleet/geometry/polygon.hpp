#pragma once

// Point in a simple polygon (zones of a site, areas the roadmap keeps out of).

#include <span>

#include "fleet/core/vec2.hpp"

namespace fleet::geometry {

/// Even-odd rule, either orientation; fewer than 3 corners contain nothing. A point exactly on an
/// edge may fall either way (the crossing test's half-open rule: bottom edges and left edges in).
bool insidePolygon(Vec2 p, std::span<const Vec2> poly);

}  // namespace fleet::geometry
