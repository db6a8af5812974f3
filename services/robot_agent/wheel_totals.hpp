#pragma once

// The driver's wheel travel totals [m] since the driver started. Two readings' totals give the
// exact motion between them, however many readings were lost in between, and across a restart of
// the agent process (the driver keeps counting): the pose file keeps them with the pose. Totals of
// two runs of the driver (it restarted and counts from zero) give nothing: the session tells them
// apart when the driver sends one.

#include <cstdint>

namespace fleet::agent {

struct WheelTotals {
  double left = 0.0;
  double right = 0.0;
  std::uint64_t session = 0;  ///< the driver's run they count in (0: not told)
};

}  // namespace fleet::agent
