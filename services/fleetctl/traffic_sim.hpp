#pragma once

// `fleetctl traffic-sim`: the traffic layer (roadmap, lifelong planner, execution by dependencies,
// station lines) driving a virtual fleet of robots that do exactly what is released to them, late
// at random (libs/traffic virtual_fleet.hpp). Seconds of wall time per simulated hour: the quick way
// to see whether the traffic layer keeps a fleet moving on a site before running the full stack.

#include <cstdint>
#include <string>
#include <vector>

namespace fleet::ctl {

struct TrafficSimOptions {
  std::string site;
  int robots = 20;
  double duration = 600.0;
  std::string seeds = "1";    ///< "1-8" or "3"
  std::string core = "sipp";  ///< the traffic layer's planner core (TrafficOptions::core)
  double spacing = 0.0;       ///< roadmap lattice spacing (m); 0: the default
  double stopChance = 0.01;
  double turnScale = 1.0;       ///< the virtual robots' turns on the spot take this times their time
  double stopGap = -1.0;        ///< m the motion gate keeps ahead of a driving robot; <0: the default
  double guidance = -1.0;       ///< flow guidance weight (RoadmapOptions::guidance); <0: the default
  int straight = -1;            ///< 1/0: planner prefers straight moves among equal ones; -1: the default
  int letPass = -1;             ///< Execution::letPass threshold in route nodes; 0 off; -1: the default
  int maxLag = -1;              ///< planner steps a robot may fall behind before a re-plan; -1: the default
  int detourAfter = -1;         ///< planner steps before a detour round standing robots; -1: the default
  double detourPenalty = -1.0;  ///< s added for entering what a standing robot excludes; <0: the default
  double occupiedCost = -1.0;   ///< s added to a move that pushes a robot; <0: the default
  int queueLength = -1;         ///< generated queue nodes per station; -1: the roadmap's default
  int stationLines = 1;         ///< 1: robots wait in line at stations' queues; 0: all planned to the dock
  int admission = 1;            ///< VirtualFleetOptions::admission: 0 none, 1 slots, 2 arrival
  int stationSlots = 0;         ///< VirtualFleetOptions::stationSlots: slots per station (0: its line)
  std::vector<std::string> stations;  ///< VirtualFleetOptions::stations
  bool json = false;
  std::string html;  ///< write a replay page of the first seed's run here (empty: none)
};

/// Exit code: 0 ran (whatever the figures), 1 a promise broken (contact, conflicting holds), 2 bad input.
int runTrafficSim(const TrafficSimOptions& options);

}  // namespace fleet::ctl
