#pragma once

// Contacts and near misses among the live figures, from what the fleet reports (there is no
// ground truth in a deployment): robot-robot from the robots' reported poses and radii, robot-person
// from the people the robots see. An event is a pair entering a state: it counts once and not again
// until the pair has left the state. States are left only beyond the threshold plus a hysteresis, so
// the jitter of two pose estimates at the threshold does not count as many events.
//
// People have no identity across reports (two robots may see the same person, a person seen now
// is not matched with one seen before), so a robot-person "pair" is a robot and whoever is nearest
// to it: a robot with a person within the margin is one near miss until no person is within it.
// Pure: no DDS, no clock, no logging; the caller decides how often to update.

#include <cstdint>
#include <limits>
#include <map>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "fleet/core/vec2.hpp"

namespace fleet::wms {

struct ProximityParams {
  /// Clearance (distance between the discs' edges) below which a pair is a near miss [m].
  double nearMissMargin = 0.2;
  /// A state is left only once the clearance exceeds its threshold by this much [m].
  double hysteresis = 0.05;
};

/// A disc: a robot (by id) or a person.
struct ProximityDisc {
  std::string id;  ///< the robot's id; ignored for a person
  Vec2 at;
  double radius = 0.0;
};

/// Counts of one kind of pair, since the counter was made.
struct ProximityCounts {
  std::uint64_t contacts = 0;    ///< pairs whose discs came to overlap
  std::uint64_t nearMisses = 0;  ///< pairs that came closer than the margin (a contact is one too)
  std::size_t inContact = 0;     ///< pairs in contact as of the last update
  std::size_t close = 0;         ///< pairs closer than the margin as of the last update
  /// The smallest clearance seen [m] (negative: overlap depth); +inf before any pair.
  double minClearance = std::numeric_limits<double>::infinity();
};

class ProximityCounter {
 public:
  explicit ProximityCounter(ProximityParams p = {}) : p_(p) {}

  /// One look at the fleet: every pair of robots and every robot with the people. A robot id that
  /// appears twice counts once (its first disc). Pairs not present any more leave their states.
  void update(const std::vector<ProximityDisc>& robots, const std::vector<ProximityDisc>& people);

  [[nodiscard]] const ProximityCounts& robotRobot() const { return robots_; }
  [[nodiscard]] const ProximityCounts& robotPerson() const { return people_; }
  [[nodiscard]] const ProximityParams& params() const { return p_; }
  /// Grows with every update that changed a figure (for sending only what changed).
  [[nodiscard]] std::uint64_t version() const { return version_; }

 private:
  struct PairState {
    bool close = false;
    bool contact = false;
  };
  /// Moves a pair's state on by its clearance `c`, counting entries into `counts`.
  void step(PairState& s, double c, ProximityCounts& counts) const;

  ProximityParams p_;
  ProximityCounts robots_;
  ProximityCounts people_;
  std::map<std::pair<std::string, std::string>, PairState> robotPairs_;  // (smaller id, larger id)
  std::map<std::string, PairState> personPairs_;                         // robot -> nearest person
  std::uint64_t version_ = 0;
};

}  // namespace fleet::wms
