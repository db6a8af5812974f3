#pragma once

#include <string>

#include "fleet/site/site.hpp"
#include "fleet/traffic/roadmap.hpp"
#include "fleet/traffic/virtual_fleet.hpp"

namespace fleet::ctl {

/// `fleetctl traffic-sim --html FILE`: one self-contained page that replays a virtual-fleet run over
/// the site's drawing (siteSvg: map, roadmap, stations, queue lines): each robot as its disc, what is
/// released to it (base, solid) and what it may expect (horizon, dashed), the station it is heading
/// for, and the queues in front of the stations as robots wait in them. Play, pause, step and a
/// time slider; no network, no libraries.
std::string trafficSimHtml(const site::Site& site, const traffic::Roadmap& roadmap,
                           const traffic::VirtualFleetResult& result, const std::string& title);

}  // namespace fleet::ctl
