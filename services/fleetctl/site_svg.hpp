#pragma once

#include <string>

#include "fleet/site/site.hpp"
#include "fleet/traffic/roadmap.hpp"

namespace fleet::ctl {

/// `fleetctl site check --svg FILE`: the site's map (obstacles, no-go, speed-limit and one-way
/// cells), its roadmap (edges, one-way ones with arrows, nodes coloured by kind, queue lines) and
/// the stations with their names, as one SVG page in the map's frame (x right, y up), with a legend.
std::string siteSvg(const site::Site& site, const traffic::Roadmap& roadmap);

}  // namespace fleet::ctl
