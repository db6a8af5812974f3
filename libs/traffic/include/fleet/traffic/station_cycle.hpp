#pragma once

// A station's least dock cycle with ideal motion (docs/algorithms.md, "Fleet bound"): the least
// time from one robot's arrival at the dock to the next robot's arrival there. The dock is a dead
// end: robots enter and leave it along its straight last leg (dock ← approach point), on which two
// robots cannot pass, so the next robot waits at the queue head (the nearest waiting point) until
// the one docked has dwelt and backed out along the leg to the approach point. From then on both
// move at once: the leaving robot drives off clear of the next one's way while the next drives
// from the queue head to the approach point and along the leg in. The next robot's disc cannot
// reach the approach point before the leaving one is a diameter (2r) past it, so
//
//   c = dwell + (|dock − approach| + max(|queueHead − approach|, 2r) + |approach − dock|) / cruise
//
// with straight lines (the leg is straight by construction; a straight line is the least way) and
// no turns (ideal). Without an approach point the leg has no length (approach = dock); without a
// queue the next robot waits a diameter away.
//
// A station with an exit (a server: left by a way of its own, roadmap.hpp) is not left along the
// leg: the leaving robot drives off to its exit while the next one comes in, so the least cycle is
// the next robot's drive from the queue head to the dock,
//
//   c = dwell + (|queueHead − approach| + |approach − dock|) / cruise
//
// (|queueHead − approach| → 2r without a queue): whatever the exit's geometry, the next robot cannot
// arrive sooner than that after the last one's dwell.

#include <optional>
#include <vector>

#include "fleet/core/vec2.hpp"
#include "fleet/traffic/roadmap.hpp"

namespace fleet::traffic {

struct DockGeometry {
  Vec2 dock;
  std::optional<Vec2> approach;  ///< start of the straight last leg
  std::vector<Vec2> queue;       ///< waiting points, nearest first
  std::optional<Vec2> exit;      ///< where the docked robot leaves to; none: back along the leg
};

/// The motion part of the cycle (the dwell comes from each visit's task): the sum in parentheses
/// above over the cruise. 0 for a cruise ≤ 0 or anything not finite (the caller checks its inputs).
[[nodiscard]] double dockMoveSeconds(const DockGeometry& g, double radius, double cruise);

/// A station's geometry on the roadmap: its dock, approach, queue head and exit nodes' positions.
[[nodiscard]] DockGeometry dockGeometry(const Graph& g, const StationNodes& s);

}  // namespace fleet::traffic
