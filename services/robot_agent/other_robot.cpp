#include "other_robot.hpp"

#include "fleet/core/clock.hpp"

namespace fleet::agent {

namespace {
constexpr double kStandingWaitS = 5.0;  // s a robot waits before others plan around it (standing)
}  // namespace

bool standing(const OtherRobot& o) {
  // A robot that has waited kStandingWaitS on end (queueing for a station, held by a person who
  // does not step aside) will most likely stand a while longer too: plan around it rather than
  // queue behind it. Two chains in 20-robot runs ended that way: robots queueing behind a robot
  // that waited on a person in an aisle, and a robot leaving a drop-off station through the queue
  // in front of it, each failing its task after 60 s.
  using Mode = OtherRobot::Mode;
  const bool waitedLong = o.mode == Mode::kWaiting && o.waitingSinceNs >= 0 &&
                          nsToSec(o.stampNs - o.waitingSinceNs) > kStandingWaitS;
  return o.mode == Mode::kLoading || o.mode == Mode::kCharging || o.mode == Mode::kFault ||
         (o.mode == Mode::kIdle && !o.hasTask) || waitedLong;
}

}  // namespace fleet::agent
