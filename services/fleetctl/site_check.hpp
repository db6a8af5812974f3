#pragma once

#include <string>

namespace fleet::ctl {

/// `fleetctl site check FILE`: loads a site (or a scenario naming one, a MovingAI .map, a ROS map
/// .yaml), prints what it holds, where a robot of `radius` (the site's when <= 0) can go and the
/// traffic roadmap built for it; `svgFile` non-empty: draws map, roadmap and stations there.
/// Exit code: 0 fine, 2 any problem (each named by file and key path; roadmap warnings do not count).
int siteCheck(const std::string& file, double radius, double mapResolution, bool asJson,
              const std::string& svgFile = "");

}  // namespace fleet::ctl
