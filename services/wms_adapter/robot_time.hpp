#pragma once

// The robot-time ledger of the live fleet (docs/algorithms.md, "Robot-time and station ledgers"):
// where each robot's time went since the adapter started, in the nine categories of
// fleet/core/robot_activity.hpp, from the RobotState samples it receives. Each sample files the time
// since the robot's previous one (by the robots' own stamps) under the previous sample's activity —
// the one the robot was in over that interval. A gap longer than kMaxGapNs (a robot silent, an
// adapter that lost it) is not filed: the ledger says where the time it saw went, not more. An
// agent that does not fill `activity` (Unset) is read by its mode and task (activityFromMode).
// No DDS, no logging.

#include <cstdint>
#include <map>
#include <string>

#include "fleet/core/robot_activity.hpp"
#include "fleet/messages/messages.hpp"

namespace fleet::wms {

class RobotTimeLedger {
 public:
  static constexpr std::int64_t kMaxGapNs = 2'000'000'000;
  /// At most this many robots are kept (a flood of made-up ids cannot grow it without bound).
  static constexpr std::size_t kMaxRobots = 10'000;

  void onState(const msg::RobotState& s);

  /// Every robot's ledger, by robot id.
  [[nodiscard]] const std::map<std::string, ActivityLedger>& robots() const { return robots_; }
  /// The fleet's: every robot's summed.
  [[nodiscard]] ActivityLedger fleet() const;

 private:
  struct Last {
    std::int64_t stampNs = 0;
    RobotActivity activity = RobotActivity::Unset;
  };
  std::map<std::string, ActivityLedger> robots_;
  std::map<std::string, Last> last_;
};

}  // namespace fleet::wms
