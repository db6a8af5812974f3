#pragma once

// The per-robot efficiency is measured while the fleet is saturated: over the window in
// which at least as many tasks wait (stored, not yet assigned) as there are robots, so that every
// robot that finishes a task can chain the next without a trip home. The rate inside that window
// is the fleet's capacity; the rate over a whole run mixes in the ramp-up from parking and the
// tail after the last task was posted. The fleet's rate is stated against the fleet bound
// (fleet_bound.hpp), not against a lone robot's run.

#include <cstddef>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "task_ledger.hpp"

namespace fleet::ctl {

struct SaturatedWindow {
  bool found = false;       ///< waiting ≥ robots held over a window of positive length
  double fromS = 0.0;       ///< first instant at which waiting ≥ robots
  double toS = 0.0;         ///< last instant at which it held (the run's end if it still held)
  double heldFraction = 0;  ///< share of [from, to] in which it held (it may dip in between)
  std::size_t done = 0;     ///< tasks first done inside (from, to]
  std::size_t robots = 0;
  std::size_t peakWaiting = 0;  ///< counted as the window is: after each stamp's last transition
  double perRobotPerH = 0.0;    ///< done ÷ robots ÷ window hours
};

/// `transitions` in the order the manager stored them (stamps in simulated ns); `endS` the run's
/// simulated end, which closes a window still open then. No window (found = false) for 0 robots,
/// A run in which fewer tasks than robots ever waited, or one that reached it only for an instant.
[[nodiscard]] SaturatedWindow saturatedWindow(const std::vector<TransitionRow>& transitions,
                                              std::size_t robots, double endS);

/// loadtest.json's "saturated": the window and its rates; {"found": false, "why": ...} without one.
[[nodiscard]] nlohmann::json saturatedJson(const SaturatedWindow& w);

/// One line for the run's summary.
[[nodiscard]] std::string saturatedLine(const nlohmann::json& saturated);

}  // namespace fleet::ctl
