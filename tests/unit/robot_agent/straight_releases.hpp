// A stand-in traffic manager for one robot on an open floor (the agent's unit tests): whenever the
// robot reports a goal it has no base to, it releases the straight way from the node the robot last
// reported to that goal, a node every 0.5 m, ending on the goal. Header-only.
#pragma once

#include <cmath>
#include <map>
#include <optional>
#include <string>
#include <utility>

#include "fleet/messages/messages.hpp"

namespace fleet::test {

class StraightReleases {
 public:
  explicit StraightReleases(std::string robot) : robot_(std::move(robot)) {}

  /// The release the robot's progress report calls for, if any.
  std::optional<msg::TrafficRelease> onProgress(const msg::TrafficProgress& p) {
    if (p.robot_id != robot_ || !p.has_goal || (releasedTo_ && *releasedTo_ == p.goal)) {
      return std::nullopt;
    }
    msg::TrafficRelease r;
    r.robot_id = robot_;
    r.epoch = 1;
    r.seq = ++seq_;
    r.ends_at_goal = true;
    const auto known = nodes_.find(p.node);
    const Vec2 from = known != nodes_.end() ? known->second : p.pose.position();
    r.base.push_back(node(known != nodes_.end() ? p.node : add(from), from));
    const Vec2 to = p.goal.position();
    const int steps = std::max(1, static_cast<int>(std::ceil(distance(from, to) / 0.5)));
    for (int i = 1; i <= steps; ++i) {
      const Vec2 at = from + (to - from) * (static_cast<double>(i) / steps);
      r.base.push_back(node(add(at), at));
    }
    releasedTo_ = p.goal;
    ++releases_;
    return r;
  }

  [[nodiscard]] int releases() const { return releases_; }

 private:
  std::int32_t add(Vec2 at) {
    nodes_[next_] = at;
    return next_++;
  }
  static msg::RouteNode node(std::int32_t id, Vec2 at) { return {id, at.x, at.y}; }

  std::string robot_;
  std::map<std::int32_t, Vec2> nodes_;
  std::int32_t next_ = 0;
  std::uint32_t seq_ = 0;
  std::optional<Pose2> releasedTo_;
  int releases_ = 0;
};

}  // namespace fleet::test
