#pragma once

// Why a robot with a task stands waiting on another robot, as the robot-time ledger's "waiting on
// another robot" is split (docs/algorithms.md, "Waiting on robots, by what the other does"): by
// what the robot it waits on (the one the execution names first) does at that moment, and, when
// that one drives, by how its way lies against the waiting robot's next one.
//
// - same way: it drives the way the waiting one is to go (less than 60° off): a robot following
//   another down a lane, kept a footprint behind;
// - head-on: it drives against that way (less than 60° off the opposite): two robots meeting in a
//   lane, one standing aside or at its end until the other has passed;
// - across: it drives across that way: a crossing, or a robot turning into or out of a lane;
// - standing: it stands without dwelling, itself waiting or planned to stand: a chain of waits, or
//   a robot parked in the way;
// - dwelling: it loads or unloads at a station the waiting one must pass or wait for;
// - none named: the execution names no robot (the plan itself keeps the robot standing: a planned
//   wait the execution does not tie to a robot).
//
// Pure: no DDS, no logging.

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "fleet/core/vec2.hpp"
#include "fleet/traffic/execution.hpp"
#include "fleet/traffic/graph.hpp"

namespace fleet::traffic {

enum class WaitCause : std::uint8_t { SameWay, HeadOn, Across, Standing, Dwelling, NoneNamed };

inline constexpr std::array<WaitCause, 6> kWaitCauses = {WaitCause::SameWay,  WaitCause::HeadOn,
                                                         WaitCause::Across,   WaitCause::Standing,
                                                         WaitCause::Dwelling, WaitCause::NoneNamed};

/// "same_way", "head_on", "across", "standing", "dwelling", "none_named".
const char* toString(WaitCause c);

/// What is seen of one wait.
struct WaitSeen {
  /// Where the waiting robot is to go: its next node less its node. Zero when it has no next node
  /// planned; the way towards the robot it waits on is taken then.
  Vec2 way;
  Vec2 at;             ///< the waiting robot's position
  bool named = false;  ///< the execution names a robot it waits on (the rest describes that robot)
  Vec2 otherAt;        ///< its position
  bool otherDriving = false;
  Vec2 otherWay;  ///< its edge (to less from) when it drives
  bool otherDwelling = false;
};

/// A robot as a fleet loop saw it at the start of a tick, before any robot moved in it.
struct WaitSnapshot {
  NodeId at = kNoNode;  ///< its last node
  NodeId to = kNoNode;  ///< the node it drives to; kNoNode: standing
  bool dwelling = false;
  /// Standing: the robot it waits on, the first the execution names; anything ≥ the robots' count
  /// when it names none (or the robot drives).
  std::size_t on = static_cast<std::size_t>(-1);
};

/// What is seen of robot r's wait, from the tick's snapshot of every robot and r's release: its
/// next node is the one after its node in its base, else the horizon's first.
WaitSeen waitSeen(const Graph& g, const std::vector<WaitSnapshot>& robots, std::size_t r,
                  const Release& release);

/// The cause, by the rules above (a lattice's edges meet at multiples of 45°: a way one bend off
/// counts as the same way or head-on). A driving robot with an edge of no length counts as
/// standing.
WaitCause classifyWait(const WaitSeen& s);

}  // namespace fleet::traffic
