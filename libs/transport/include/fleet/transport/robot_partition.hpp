#pragma once

// Per-robot topics: what a robot says (its state, task status, traffic progress, predicted discs,
// the people it sees) and the velocity commands it is given travel in a DDS partition of its own,
// "robot/<id>". Under DDS
// Security an agent's permissions name only its robots' partitions, so its certificate cannot
// create a writer in another robot's partition; readers subscribe to "robot/*" and drop a sample
// whose robot id is not the partition its writer is in, so a writer in its own partition cannot
// speak for another robot either. Without security the same partitions are used: one code path,
// tested by every multi-process test. docs/operator-guide.md ("Security: DDS") has the table.
//
// DDS orders samples per writer only: a command from a robot's writer may arrive after the StepDone
// written after it from another writer (a reader matched with a writer it has just discovered holds
// that writer's first samples until a heartbeat; a lost datagram is resent later). So in lockstep a
// StepDone names the last command it covers for each robot and the simulator waits for those
// (sim/lockstep.hpp), and an agent registers only once its command writers have matched a reader.

#include <string>
#include <string_view>

#include "fleet/messages/messages.hpp"

namespace fleet::transport {

inline constexpr std::string_view kRobotPartitionPrefix = "robot/";
/// What the readers of a per-robot topic subscribe to (Cyclone matches it against each writer's).
inline constexpr const char* kAnyRobotPartition = "robot/*";

/// "robot/<id>". Robot ids are [A-Za-z0-9_.:-] (core/ids.hpp), so never a partition pattern.
inline std::string robotPartition(std::string_view robot) {
  return std::string(kRobotPartitionPrefix) + std::string(robot);
}

/// Which robot a sample of a per-robot topic speaks for; topics without one are not per robot.
/// An empty id means "no robot": the sample travels in the default partition (a human's discs,
/// written by the simulator).
template <class T>
struct RobotOf {
  static constexpr bool kPerRobot = false;
};
template <class T>
requires requires(const T& m) {
  { m.robot_id } -> std::convertible_to<std::string>;
} &&(std::same_as<T, msg::RobotState> || std::same_as<T, msg::TaskStatus> ||
     std::same_as<T, msg::TrafficProgress> || std::same_as<T, msg::VelocityCommand> ||
     std::same_as<T, msg::PeopleSeen>)struct RobotOf<T> {
  static constexpr bool kPerRobot = true;
  /// Samples without a robot travel in the default partition too (never for these types).
  static constexpr bool kAlsoDefault = false;
  static const std::string& of(const T& m) { return m.robot_id; }
};
template <>
struct RobotOf<msg::PredictedDiscs> {
  static constexpr bool kPerRobot = true;
  static constexpr bool kAlsoDefault = true;
  static const std::string& of(const msg::PredictedDiscs& m) {
    static const std::string none;
    return m.kind == msg::SourceKind::Robot ? m.source_id : none;
  }
};

}  // namespace fleet::transport
