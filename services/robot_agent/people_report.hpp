#pragma once

// The people a robot sees, published for operators (the PeopleSeen topic): in a deployment there
// is no simulator ground truth, only what the robots' sensors see. Sent every periodNs of the
// agent's clock, not every cycle, so that hundreds of robots do not load the bus with lists that
// change little between cycles; robots of one process are given phases apart so their reports do
// not come in one burst.

#include <cstdint>
#include <optional>
#include <string>

#include "fleet/messages/messages.hpp"
#include "localizer.hpp"

namespace fleet::agent {

/// 4 Hz: a walking person moves ~0.3 m between reports, finer than the page draws.
inline constexpr std::int64_t kPeopleSeenPeriodNs = 250'000'000;

class PeopleReport {
 public:
  /// The first report goes out at the first call at or after (first call + phaseNs).
  explicit PeopleReport(std::int64_t periodNs = kPeopleSeenPeriodNs, std::int64_t phaseNs = 0)
      : periodNs_(periodNs), phaseNs_(phaseNs) {}

  /// The report due at `nowNs`, if one is. Nothing while the robot has no reading or has lost its
  /// sensor stream (it does not know who is around: readers let the last list age out). At most
  /// msg::kMaxPeopleSeen people, the nearest to the robot first kept.
  std::optional<msg::PeopleSeen> due(const std::string& robot, std::int64_t nowNs, const Perception& seen,
                                     bool sensorLost);

 private:
  std::int64_t periodNs_;
  std::int64_t phaseNs_;
  std::int64_t nextNs_ = -1;  // not before this time (-1: no call yet)
};

}  // namespace fleet::agent
