#pragma once

// The driver's wheel travel totals [m] since the driver started. Two readings' totals give the
// exact motion between them, however many readings were lost in between, and across a restart of
// the agent process (the driver keeps counting): the pose file keeps them with the pose.

namespace fleet::agent {

struct WheelTotals {
  double left = 0.0;
  double right = 0.0;
};

}  // namespace fleet::agent
