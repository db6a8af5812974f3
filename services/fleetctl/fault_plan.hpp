#pragma once

// Faults a load test injects, parsed from `--fault` options. Times are simulated seconds since the
// start of the run; down times are wall seconds (a process is down for real time, not sim time).
//   kill-agent@T[+D][:K]   SIGKILL agent process K (default 0) at T, restart it D s later (default 2)
//   kill-manager@T[+D]     SIGKILL the fleet manager at T, restart it D s later (default 1); with
//                          --store postgresql the active one of the two (standby_managers.hpp)
//   kill-traffic@T[+D]     SIGKILL the traffic manager at T, restart it D s later (default 1): robots
//                          stop at the end of what was released to them; the new one rebuilds its
//                          state from their progress reports
//   stall:ROBOT@T+D        SIGSTOP the agent process of ROBOT (it runs alone) at T, SIGCONT D s later
//   drop-dds=F             every process drops the fraction F (0..0.5) of its outgoing DDS packets
//   close@T+D:X1,Y1,X2,Y2,X3,Y3[,...]
//                          close the roadmap inside that polygon (m, map frame) at T for D *simulated*
//                          seconds, through the WMS adapter (PUT / DELETE /v1/traffic/closures):
//                          reserved traffic plans every robot round it
//   hide-landmarks@T+D     no robot sees a landmark from T for D *simulated* seconds (the simulator
//                          leaves the bearings out of every SensorFrame): localization on odometry,
//                          compass and laser lines alone

#include <string>
#include <vector>

#include "fleet/core/expected.hpp"

namespace fleet::ctl {

struct Fault {
  enum class Kind { KillAgent, KillManager, KillTraffic, StallRobot, DropDds, HideLandmarks, CloseArea };
  Kind kind = Kind::KillAgent;
  double atS = 0.0;          // simulated seconds
  double downS = 0.0;        // wall seconds (hide-landmarks: simulated seconds)
  int agent = 0;             // kill-agent: which agent process
  std::string robot;         // stall: which robot
  double fraction = 0;       // drop-dds
  std::vector<double> area;  // close: X1, Y1, X2, Y2, ... (at least 3 corners)
};

/// Parses every spec; the error lists each bad one with what was expected.
Expected<std::vector<Fault>> parseFaults(const std::vector<std::string>& specs);

/// The one-line form of a fault for logs and reports (parses back to the same fault).
std::string describe(const Fault& f);

/// The supervised process a kill fault kills ("" for the other kinds; kill-agent's depends on
/// how robots are spread over agent processes, so the caller names it).
std::string killedService(const Fault& f);

/// The DDS drop fraction of the plan (0 when none); at most one drop-dds is allowed.
double dropFraction(const std::vector<Fault>& faults);

}  // namespace fleet::ctl
