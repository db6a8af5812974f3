#include "traffic_sim.hpp"

#include <cstdio>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>

#include "fleet/core/config.hpp"
#include "fleet/service/site_stations.hpp"
#include "fleet/traffic/roadmap.hpp"
#include "fleet/traffic/virtual_fleet.hpp"
#include "traffic_sim_view.hpp"

namespace fleet::ctl {

int runTrafficSim(const TrafficSimOptions& o) {
  const auto site = service::loadSiteFile(o.site);
  if (!site) {
    std::cerr << "fleetctl traffic-sim: " << site.error().message << "\n";
    return 2;
  }
  int first = 0;
  int last = 0;
  char dash = 0;
  const int n = std::sscanf(o.seeds.c_str(), "%d%c%d", &first, &dash, &last);
  if (n == 1) {
    last = first;
  }
  if ((n != 1 && (n != 3 || dash != '-')) || first < 0 || last < first) {
    std::cerr << "fleetctl traffic-sim: --seeds " << o.seeds << ": give a seed or a range like 1-8\n";
    return 2;
  }
  // A page that cannot be written is bad input: say so before a run that may take minutes.
  if (!o.html.empty() && !std::ofstream(o.html)) {
    std::cerr << "fleetctl traffic-sim: cannot write " << o.html << "\n";
    return 2;
  }
  traffic::RoadmapOptions ro;
  ro.spacing = o.spacing;
  if (o.queueLength >= 0)
    ro.queueLength = o.queueLength;
  if (o.stopGap >= 0.0)
    ro.stopGap = o.stopGap;
  auto roadmap = traffic::buildRoadmap(*site, ro);
  int rc = 0;
  nlohmann::json all = nlohmann::json::array();
  for (int seed = first; seed <= last; ++seed) {
    traffic::VirtualFleetOptions v;
    v.robots = static_cast<std::size_t>(o.robots);
    v.duration = o.duration;
    v.seed = static_cast<std::uint64_t>(seed);
    v.stopChance = o.stopChance;
    v.stationLines = o.stationLines != 0;
    v.stationCap = static_cast<std::size_t>(o.stationCap);
    if (o.maxLag > 0)
      v.traffic.maxLag = o.maxLag;
    if (o.letPass >= 0)
      v.traffic.letPassBehind = o.letPass;
    if (o.straight >= 0) {
      v.traffic.pibt.preferStraight = o.straight != 0;
      v.traffic.pibt.tieTolerance = o.straight != 0 ? 1e-3F : 0.0F;
    }
    if (o.detourAfter >= 0)
      v.traffic.pibt.detourAfter = o.detourAfter;
    if (o.detourPenalty >= 0.0)
      v.traffic.pibt.detourPenalty = static_cast<float>(o.detourPenalty);
    const bool record = !o.html.empty() && seed == first;
    if (record)
      v.recordEvery = 0.5;
    traffic::VirtualFleetResult r;
    try {
      r = traffic::runVirtualFleet(roadmap, v);
    } catch (const std::invalid_argument& e) {
      std::cerr << "fleetctl traffic-sim: " << e.what() << "\n";
      return 2;
    }
    if (r.contacts > 0 || r.holdViolations > 0)
      rc = 1;
    if (record) {
      std::ofstream out(o.html);
      out << trafficSimHtml(*site, roadmap, r,
                            "traffic-sim " + site->name + ", " + std::to_string(o.robots) + " robots, seed " +
                                std::to_string(seed));
      if (!out) {
        std::cerr << "fleetctl traffic-sim: cannot write " << o.html << "\n";
        return 2;
      }
    }
    if (o.json) {
      all.push_back({{"seed", seed},
                     {"robots", r.robots},
                     {"duration_s", r.duration},
                     {"tasks_done", r.tasksDone},
                     {"tasks_per_hour", r.tasksPerHour},
                     {"mean_task_s", r.meanTaskTime},
                     {"min_separation_m", r.minSeparation},
                     {"contacts", r.contacts},
                     {"hold_violations", r.holdViolations},
                     {"longest_wait_s", r.longestWait},
                     {"replans", r.replans},
                     {"evasions", r.evasions},
                     {"detours", r.detours},
                     {"escalations", r.escalations},
                     {"untangles", r.untangles},
                     {"passes", r.passes},
                     {"update_p99_ms", r.updateP99Ms},
                     {"density", r.density},
                     {"time_driving", r.driving},
                     {"time_dwelling", r.dwelling},
                     {"time_waiting_on_others", r.waitingOnOthers},
                     {"time_planned_to_stand", r.standingPlanned},
                     {"stalls", r.stalls}});
    } else {
      std::cout << "seed " << seed << ": " << traffic::formatResult(r) << "\n";
      for (const auto& s : r.stalls)
        std::cout << "  stalled: " << s << "\n";
    }
  }
  if (o.json)
    std::cout << all.dump(1) << "\n";
  return rc;
}

}  // namespace fleet::ctl
