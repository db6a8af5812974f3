#pragma once

// What a robot held up by something in its way does about it, cycle after cycle of the hold: plan
// around a robot that will stand there a while, yield (back out or back off) when it has the lower
// priority, try a way around the blocking point every while, and in the end fail the task. The
// priority rule is a total order (a person before any robot, a robot on an order before one driving
// home, then the smaller id; a robot right at the back of a waiting one makes room whatever the
// ids), so every wait cycle is broken.

#include <cstdint>
#include <string>
#include <vector>

#include "fleet/core/vec2.hpp"
#include "other_robot.hpp"

namespace fleet::agent {

struct StandoffParams {
  std::string selfId;            ///< this robot's id (the priority rule compares ids)
  double radius = 0.3;           ///< of every robot [m]
  double blockedBackoffS = 4.0;  ///< held this long, the one that yields backs off
  double blockedFailS = 60.0;    ///< held this long, the task fails
};

/// One cycle of a hold.
struct Standoff {
  std::int64_t nowNs = 0;
  std::int64_t sinceNs = 0;      ///< when the hold began
  bool byRobot = false;          ///< a robot holds this one up (else a person or something static)
  std::string blocker;           ///< its id ("robot": not known which), "human", or empty (static)
  bool blockPointKnown = false;  ///< the stop rule knows where the obstacle is (a detour can avoid it)
  bool homing = false;           ///< this robot drives home (no order)
  Vec2 position;                 ///< of this robot
};

enum class StandoffMove {
  kWait,                ///< nothing to do yet
  kPlanAroundStanding,  ///< the blocker will stand a while: re-plan now (the hold's clock runs on)
  kYield,   ///< back out along the trail, else back off if the rear is clear; neither: cannotYield()
  kDetour,  ///< re-plan around the blocking point
  kFail,    ///< fail the task
};

struct StandoffDecision {
  StandoffMove move = StandoffMove::kWait;
  bool newStandoff = false;  ///< the hold has just passed 1 s: a standoff to count
  int waitCycles = 0;        ///< ... on a robot that waits itself (a cycle of the wait-for graph)
};

class StandoffArbiter {
 public:
  explicit StandoffArbiter(StandoffParams params) : p_(std::move(params)) {}

  /// The move for this cycle of the hold. `others`: every other robot as last reported.
  StandoffDecision decide(const Standoff& s, const std::vector<OtherRobot>& others);
  /// The robot should yield but can neither back out nor back off: what it does instead.
  StandoffMove cannotYield(const Standoff& s) { return otherwise(s); }

 private:
  /// Whether this robot gives way to the blocker.
  [[nodiscard]] bool yields(const Standoff& s, const std::vector<OtherRobot>& others) const;
  /// This robot stands right at the back of `o` (in the corridor `o` would back into).
  [[nodiscard]] bool behind(const OtherRobot& o, Vec2 self) const;
  /// Detour around the blocking point, fail, or wait.
  StandoffMove otherwise(const Standoff& s);

  StandoffParams p_;
  std::int64_t countedNs_ = -1;             // the hold already counted as a standoff (its start)
  std::int64_t lastDetourNs_ = -1;          // when the last detour around the blocking point was tried
  std::int64_t lastStandingDetourNs_ = -1;  // ... around a standing robot (re-planned with it blocked)
};

}  // namespace fleet::agent
