#pragma once

// What a robot is doing, for the robot-time ledger: every instant of a robot's time falls in exactly
// one of these. The robot agent says it in RobotState.activity (libs/messages mirrors this enum);
// `Unset` is what an agent that does not fill the field sends, and readers then derive what they can
// from the robot's mode (activityFromMode). Pure: no DDS, no logging.

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

namespace fleet {

enum class RobotActivity : std::uint8_t {
  Unset,           ///< not said (an agent that predates the field)
  NoTask,          ///< no task: parked, or driving home/to parking without a task
  Driving,         ///< driving toward its task's station
  TurningDocking,  ///< turning on the spot, or on a station's last leg in or out
  Dwelling,        ///< loading or unloading at a station
  WaitingOnRobot,  ///< standing for another robot (traffic release, station line, a standoff)
  HeldByPerson,    ///< standing or slowed for a person in its way
  HeldBySafety,    ///< stopped by its own safety layer (protective stop, no admissible motion)
  Charging,
  Faulted,
};

inline constexpr std::size_t kRobotActivities = 10;  ///< including Unset
/// The ledger's categories: every activity but Unset, in the enum's order.
inline constexpr std::array<RobotActivity, 9> kLedgerActivities = {
    RobotActivity::NoTask,       RobotActivity::Driving,        RobotActivity::TurningDocking,
    RobotActivity::Dwelling,     RobotActivity::WaitingOnRobot, RobotActivity::HeldByPerson,
    RobotActivity::HeldBySafety, RobotActivity::Charging,       RobotActivity::Faulted};

/// snake_case names, as in loadtest.json: "unset", "no_task", "driving", "turning_docking",
/// "dwelling", "waiting_on_robot", "held_by_person", "held_by_safety", "charging", "faulted".
const char* toString(RobotActivity a);
/// The inverse of toString; false for an unknown name.
bool parseRobotActivity(std::string_view name, RobotActivity& out);

/// What the robot's mode and task say when its activity is Unset: idle without a task → no task,
/// moving → driving, loading → dwelling, charging → charging, fault → faulted, waiting and blocked
/// → waiting on another robot; idle with a task (between an assignment and the first motion, or
/// standing for a release) → waiting on another robot. `mode` is RobotMode's text name ("idle",
/// "moving", "waiting", "loading", "charging", "blocked", "fault"); anything else → no task.
RobotActivity activityFromMode(std::string_view mode, bool hasTask);

/// Time per category for one robot (or summed over a fleet). `add` files seconds under one
/// activity (Unset is filed as NoTask: a ledger has no unknown row); shares are of the total, so
/// they add up to 1 whenever anything was filed.
class ActivityLedger {
 public:
  void add(RobotActivity a, double seconds);
  void add(const ActivityLedger& other);
  [[nodiscard]] double seconds(RobotActivity a) const { return s_[static_cast<std::size_t>(a)]; }
  [[nodiscard]] double total() const;
  [[nodiscard]] double share(RobotActivity a) const;

 private:
  std::array<double, kRobotActivities> s_{};
};

}  // namespace fleet
