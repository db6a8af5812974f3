#pragma once

#include "fleet/core/config.hpp"
#include "fleet/traffic/roadmap.hpp"

namespace fleet::traffic {

/// The "roadmap" object of a service's config (spacing, cruise_speed, margin, queue_length, guidance,
/// diagonals): the traffic manager plans on the roadmap it describes, and the fleet manager costs
/// tasks and sizes station lines on the same one, so both read it here. Problems go to `cfg`.
traffic::RoadmapOptions readRoadmapOptions(Config cfg);

}  // namespace fleet::traffic
