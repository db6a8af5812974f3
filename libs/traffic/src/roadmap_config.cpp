#include "fleet/traffic/roadmap_config.hpp"

namespace fleet::traffic {

traffic::RoadmapOptions readRoadmapOptions(Config r) {
  traffic::RoadmapOptions o;
  r.rejectUnknownKeys(
      {"spacing", "cruise_speed", "margin", "queue_length", "diagonals", "radius", "guidance"});
  o.spacing = r.number("spacing", 0.0, {0.0, 10.0});
  // 0: the site's robot. Larger: a fleet with vehicles larger than the site's robot (VDA 5050
  // vehicles are refused when their footprint does not fit the roadmap's robot).
  o.radius = r.number("radius", 0.0, {0.0, 10.0});
  o.cruiseSpeed = r.number("cruise_speed", o.cruiseSpeed, {0.0, 10.0, true});
  o.margin = r.number("margin", o.margin, {0.0, 2.0});
  o.queueLength = static_cast<int>(r.integer("queue_length", o.queueLength, {0, 50}));
  o.diagonals = r.boolean("diagonals", o.diagonals);
  // Flow guidance (guidance.hpp): 0 off; the default 0.5 makes the small warehouse's 10 and 20
  // robots and the site for 300 faster, the site for 100 within its seeds' spread
  // (docs/benchmarks.md, "Flow guidance").
  o.guidance = r.number("guidance", o.guidance, {0.0, 100.0});
  return o;
}

}  // namespace fleet::traffic
