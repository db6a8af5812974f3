#include "standoff_arbiter.hpp"

#include "axis_offset.hpp"
#include "fleet/core/clock.hpp"

namespace fleet::agent {

StandoffDecision StandoffArbiter::decide(const Standoff& s, const std::vector<OtherRobot>& others) {
  StandoffDecision d;
  const double blockedS = nsToSec(s.nowNs - s.sinceNs);
  if (blockedS > 1.0 && countedNs_ != s.sinceNs) {
    countedNs_ = s.sinceNs;
    d.newStandoff = true;
    for (const auto& o : others) {
      // Waiting on a robot that waits too: a cycle of the wait-for graph (or a chain into one).
      // The priority rule below breaks any cycle.
      if (s.byRobot && o.id == s.blocker && o.mode == OtherRobot::Mode::kWaiting) {
        ++d.waitCycles;
      }
    }
  }
  // Behind a robot that will stand there for a while (loading, charging, parked, faulted): plan
  // around it now instead of queueing (the plan blocks the cells of every standing robot).
  if (s.byRobot && blockedS > 1.0 &&
      (lastStandingDetourNs_ < 0 || nsToSec(s.nowNs - lastStandingDetourNs_) > 3.0)) {
    for (const auto& o : others) {
      if (o.id == s.blocker && standing(o)) {
        // (A timer of its own: sharing the one of the detour around the blocking point below,
        // this re-plan every 3 s, the same path each time, kept that one from ever running.)
        lastStandingDetourNs_ = s.nowNs;
        d.move = StandoffMove::kPlanAroundStanding;
        return d;
      }
    }
  }
  d.move = blockedS > p_.blockedBackoffS && yields(s, others) ? StandoffMove::kYield : otherwise(s);
  return d;
}

bool StandoffArbiter::yields(const Standoff& s, const std::vector<OtherRobot>& others) const {
  // A person who does not step aside, or two robots face to face: the one of lower priority backs
  // off if nothing is behind, then tries another way around, rather than wait forever. Priority:
  // a robot on an order before one driving home, then the smaller id. It is a total order, so in
  // every wait cycle some robot waits on one of higher priority and yields.
  bool gives = !s.byRobot;
  if (s.byRobot && s.blocker != "robot") {
    gives = p_.selfId > s.blocker;
    for (const auto& o : others) {
      if (o.id == s.blocker && s.homing != !o.hasTask) {
        gives = s.homing;  // exactly one of the two drives home: that one yields
      }
      if (o.id == s.blocker && o.mode == OtherRobot::Mode::kWaiting && behind(o, s.position)) {
        // Right at the back of a robot that waits: it may be yielding itself (to a person, to a
        // robot of higher priority) and need the room this one takes. Make it, whatever the
        // priority; the one ahead faces away, so it does not wait on this one (no cycle).
        gives = true;
      }
    }
  }
  return gives;
}

bool StandoffArbiter::behind(const OtherRobot& o, Vec2 self) const {
  const auto [along, lateral] = axisOffset({o.pos.x, o.pos.y, o.theta}, self);
  return along < 0.0 && -along < 2.0 * p_.radius + 0.35 && lateral < 2.0 * p_.radius + 0.05;
}

StandoffMove StandoffArbiter::otherwise(const Standoff& s) {
  const double blockedS = nsToSec(s.nowNs - s.sinceNs);
  if (blockedS > 2.0 * p_.blockedBackoffS && s.blockPointKnown &&
      (lastDetourNs_ < 0 || nsToSec(s.nowNs - lastDetourNs_) > 2.0 * p_.blockedBackoffS)) {
    // Try a way around what stands in the way, again every while: in a queue of robots nobody
    // can back off, and the one ahead may have moved aside since the last attempt.
    lastDetourNs_ = s.nowNs;
    return StandoffMove::kDetour;
  }
  if (blockedS > p_.blockedFailS) {
    return StandoffMove::kFail;
  }
  return StandoffMove::kWait;
}

}  // namespace fleet::agent
