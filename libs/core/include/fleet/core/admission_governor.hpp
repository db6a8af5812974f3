#pragma once

// How many tasks the stations' lines admit, set by what the traffic then does (docs/algorithms.md,
// "Admission governed by the waiting"). Admission by slots counts a robot at its drop-off for the
// whole task, so a line of four places admits four tasks however far away their robots are: on a
// site large for its robots (300 on the site for 300) two thirds of the robot time has no task
// while thousands wait. More slots there are a third more tasks, but the same slots on a site as
// full as its lanes carry (100 on the site for 100) are a fifth fewer: the robots let in wait on
// each other. No one number fits every site (docs/benchmarks.md, "Wider slots than the lines").
//
// The governor scales every line's slots by a factor k ≥ 1 and moves k by what the fleet's robot
// time did over the last window: robots idle while tasks wait and few of them waiting on another
// robot, one step up; many waiting on another robot, one step down. Pure: no clock of its own, no
// DDS, no logging.

#include <cstddef>

#include "fleet/core/robot_activity.hpp"

namespace fleet {

struct AdmissionGovernorConfig {
  double windowS = 30.0;  ///< robot time summed over this much fleet time decides one step
  /// Waiting on another robot below this share: room for more work. Above waitHigh: too many
  /// robots in each other's way. On the full stack 100 robots on the site for 100 lost a quarter of
  /// their tasks with a band of 8–15 % (docs/algorithms.md, "Admission governed by the waiting").
  double waitLow = 0.05;
  double waitHigh = 0.10;
  double idleLeast = 0.05;  ///< a step up only while more than this share has no task
  double step = 0.25;       ///< k's change per window
  double maxScale = 4.0;    ///< k at most (and 1 at least: the lines' own places)
};

class AdmissionGovernor {
 public:
  explicit AdmissionGovernor(AdmissionGovernorConfig c = {}) : c_(c) {}

  /// Files `seconds` of one robot's time under `a` (call for every robot every tick).
  void add(RobotActivity a, double seconds) { window_.add(a, seconds); }

  /// Ends the window when `windowS` of fleet time has passed since the last step: `elapsedS` is the
  /// fleet time since the previous call, `tasksHeld` whether any task waits for a place in a line.
  /// Returns true when k changed.
  bool tick(double elapsedS, bool tasksHeld);

  /// The factor on every line's places: floor(k × places) slots.
  [[nodiscard]] double scale() const { return k_; }
  /// The slots a line of `places` admits now.
  [[nodiscard]] std::size_t slots(std::size_t places) const;
  /// The last window's shares (what the last step was decided on).
  [[nodiscard]] double lastWaitingShare() const { return lastWaiting_; }
  [[nodiscard]] double lastIdleShare() const { return lastIdle_; }

 private:
  AdmissionGovernorConfig c_;
  ActivityLedger window_;
  double sinceStepS_ = 0.0;
  double k_ = 1.0;
  double lastWaiting_ = 0.0;
  double lastIdle_ = 0.0;
  bool held_ = false;  // a task was held in this window
};

}  // namespace fleet
