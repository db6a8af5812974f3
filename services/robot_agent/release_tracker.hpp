#pragma once

// What the traffic manager released to this robot and how far along it the robot is ("reserved"
// traffic, libs/traffic/include/fleet/traffic/execution.hpp): which releases to take, the base the
// robot may drive, the last node it reached (it holds that node until it reports the next one), and
// how far it still may go. Pure bookkeeping: the agent drives, this keeps count.
//
// A release is taken when it is newer than the last one of its epoch and starts at the node the
// robot last reported; a new epoch (a restarted traffic manager) when it starts at that node or at
// A node next to the robot (the restarted manager places it by its pose). Anything else is ignored
// and counted: the robot keeps what it had, which never lets it drive further than was released.

#include <cstdint>
#include <functional>
#include <optional>
#include <vector>

#include "fleet/core/vec2.hpp"

namespace fleet::agent {

/// A roadmap node as a release names it.
struct BaseNode {
  std::int32_t id = -1;
  Vec2 at;
};

struct Release {
  std::uint32_t epoch = 0;
  std::uint32_t seq = 0;
  std::vector<BaseNode> base;  ///< base[0]: the node the robot last reported; empty: hold where it is
  bool endsAtGoal = false;     ///< the base's last node is the robot's goal
};

struct ReleaseParams {
  /// A node is reached within this distance of it [m] ...
  double reachTolerance = 0.15;
  /// ... or once passed along the base, this close to it [m] (a local planner cuts corners).
  double passLateral = 0.3;
  /// A new epoch's first node may lie this far from the robot [m]: about the diagonal of the
  /// roadmap's 0.5 m lattice plus tracking error, so only the node next to the robot qualifies.
  double placeRadius = 0.75;
  /// The projection on the base looks this far past the robot's progress [m], so a base that comes
  /// back past where it went (into a station spur and out) does not skip the spur.
  double searchWindow = 1.0;
  /// A node where the base turns by more than this [rad] (back along the lane beside it, or round a
  /// 135° corner) ends the way to drive (aheadToTurnBack) and the projection until it is reached:
  /// past it the base runs back beside itself, and the nearest point of a robot on the way out can
  /// lie on the way back.
  double turnBack = 2.0;
  /// ... and so does a node after which the base comes back within this distance [m] of a node it
  /// passed more than twice as far back along the base (a loop round a shelf's end, a U-turn over
  /// two corners): the projection would take the robot for on the way back and skip the loop
  /// (one robot stood 300 s 0.14 m from its base's last node, a loop's end, with six robots
  /// waiting on it: 20-robot scenario under load).
  double comesBack = 0.6;
};

enum class ReleaseVerdict {
  kAccepted,
  kStale,     ///< not newer than the last release of its epoch
  kOffNode,   ///< does not start at the robot's node (nor, for a new epoch, next to the robot)
  kMalformed  ///< a node position that is not a number
};

struct ReleaseCounts {
  std::uint64_t accepted = 0;
  std::uint64_t foreign = 0;  ///< for another robot (counted by the caller, see noteForeign)
  std::uint64_t stale = 0;
  std::uint64_t offNode = 0;
  std::uint64_t malformed = 0;
  [[nodiscard]] std::uint64_t ignored() const { return foreign + stale + offNode + malformed; }
};

/// The largest speed [m/s] from which a robot braking at `accel` stops within `distance` when the
/// command takes effect `latency` s late (one control period): v·latency + v²/(2·accel) = distance.
double stoppingSpeed(double distance, double accel, double latency);

class ReleaseTracker {
 public:
  explicit ReleaseTracker(ReleaseParams params = {}) : p_(params) {}

  /// Takes `r` or says why not; `here` is the robot's position (for a new epoch's placement).
  ReleaseVerdict offer(const Release& r, Vec2 here);
  /// A release for another robot reached this one (counted only).
  void noteForeign() { ++counts_.foreign; }

  /// Marks the base nodes the robot at `here` has reached, in order (reaching a node implies the
  /// ones before it). True when the last reached node changed.
  bool advance(Vec2 here);

  [[nodiscard]] bool hasRelease() const { return have_; }
  [[nodiscard]] std::uint32_t epoch() const { return epoch_; }
  /// The last node reached (or placed on by a release); -1 before any release.
  [[nodiscard]] std::int32_t node() const { return node_; }
  /// Grows with every release taken: the path to drive has to be rebuilt.
  [[nodiscard]] std::uint64_t revision() const { return revision_; }
  [[nodiscard]] bool endsAtGoal() const { return endsAtGoal_; }
  /// Base nodes after the last one reached (none: nothing to drive until the next release).
  [[nodiscard]] bool nodesAhead() const { return have_ && reached_ + 1 < base_.size(); }
  /// Where the last node reached is, if any.
  [[nodiscard]] std::optional<Vec2> at() const;
  /// The next base node to reach, if any.
  [[nodiscard]] std::optional<Vec2> next() const;
  /// The base's last node, if any.
  [[nodiscard]] std::optional<Vec2> end() const;
  /// The robot is on the base's last leg (its last node is the next one).
  [[nodiscard]] bool onLastLeg() const { return have_ && reached_ + 2 == base_.size(); }
  /// Arc length [m] from the robot's projection on the base to its end (as of advance()).
  [[nodiscard]] double remaining() const;
  struct Turn {
    double distance = 0.0;  ///< arc length from the robot's projection [m]
    Vec2 at;                ///< the node
  };
  /// The next node ahead where the base turns by more than `angle` [rad], or by more than
  /// `tightAngle` at a node `tight` says is tight (none: it runs straight to its end).
  [[nodiscard]] std::optional<Turn> nextTurn(double angle, double tightAngle = 0.0,
                                             const std::function<bool(Vec2)>& tight = {}) const;
  /// The way to drive: `here`, then the base nodes not yet passed.
  [[nodiscard]] std::vector<Vec2> ahead(Vec2 here) const;
  struct Way {
    std::vector<Vec2> points;  ///< `here`, then base nodes
    std::optional<std::int32_t>
        turnsBackAt;  ///< the node the way stops at, where the base turns back (none: its end)
  };
  /// ahead(), up to the first node where the base turns by more than ReleaseParams::turnBack (that
  /// node included). A base that turns back runs beside itself (out along a queue and back along the
  /// lane next to it): a path follower projecting the robot onto the nearest leg within its window
  /// takes the way back for the way out and the base for driven.
  [[nodiscard]] Way aheadToTurnBack(Vec2 here) const;
  [[nodiscard]] const ReleaseCounts& counts() const { return counts_; }

 private:
  void take(const Release& r);
  /// How far the base turns at node k (0 < k < size - 1) [rad, 0..π].
  [[nodiscard]] double turnAt(std::size_t k) const;
  /// The first node after the last one reached where the base turns back (the last node if none).
  [[nodiscard]] std::size_t firstTurnBack() const;
  /// Base node j lies within ReleaseParams::comesBack of a node from the robot's on that is more
  /// than twice that further back along the base.
  [[nodiscard]] bool comesBackTo(std::size_t j) const;
  /// Cuts the base after the last node reached (an empty base: hold where it is).
  void hold();

  ReleaseParams p_;
  bool have_ = false;
  std::uint32_t epoch_ = 0;
  std::uint32_t seq_ = 0;
  std::vector<BaseNode> base_;
  std::vector<double> arc_;  // arc length from base_[0] to each node
  bool endsAtGoal_ = false;
  std::int32_t node_ = -1;
  std::size_t reached_ = 0;  // index in base_ of node_
  double progress_ = 0.0;    // arc length of the robot's projection on the base (never goes back)
  double beyondEnd_ = 0.0;   // how far the robot is past the base's end along its last leg
  std::uint64_t revision_ = 0;
  ReleaseCounts counts_;
};

}  // namespace fleet::agent
