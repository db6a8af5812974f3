#pragma once

// The last pose of each robot a robot_agent process hosts, kept in a file (`--pose-file`) so that
// a restarted process starts each robot's localization where the robot is, not at its parking
// place. A process restarted with every robot seeded at its start pose had the robots it hosted
// 12-16 m from where they believed they were: its line matches were rejected by the gate, so it
// never found them again, and one robot following its release in the wrong place touched a shelf
// (LoadtestE2E.ReservedTrafficThroughEveryFault...; docs/algorithms.md, "Restarting where the
// robot is"). A real base keeps its last pose over a reboot the same way.
//
// The file is JSON, {"robots": {"r7": {"x": .., "y": .., "theta": .., "saved_unix_ms": ..,
// "wheel_left_total": .., "wheel_right_total": .., "driver_session": ..}}} (the wheel totals
// optional, both or neither; the driver's session, the run they count in, only with them),
// written whole to a temporary file and renamed over the old one, so a process killed while
// writing leaves the previous file. A pose older than `maxAgeS` when read is not used (the robot
// may have been moved while nobody watched it).

#include <cstdint>
#include <map>
#include <optional>
#include <string>

#include "fleet/core/expected.hpp"
#include "fleet/core/pose2.hpp"
#include "wheel_totals.hpp"

namespace fleet::agent {

struct SavedPose {
  Pose2 pose;
  std::int64_t savedUnixMs = 0;  ///< wall clock (ms since the epoch) when it was written
  /// The driver's wheel totals the pose is as of: with them the roll since is known exactly.
  std::optional<WheelTotals> wheels;
};

using SavedPoses = std::map<std::string, SavedPose>;

/// A saved pose is used when at most this old (wall clock) when the process starts.
constexpr double kPoseFreshS = 600.0;
/// The file is written this often, of the agent's clock (simulated time in lockstep: a run
/// faster than real time writing by the wall clock left the pose a metre behind).
constexpr std::int64_t kPoseWritePeriodMs = 200;

/// Reads a pose file. A missing file is an empty map; anything else wrong (not JSON, a robot
/// whose pose is not three finite numbers) is an error naming the file and the key path.
Expected<SavedPoses> readPoseFile(const std::string& path);

/// Writes `poses` to `path` through a temporary file renamed over it.
Expected<void> writePoseFile(const std::string& path, const SavedPoses& poses);

/// The saved poses no older than `maxAgeS` at `nowUnixMs` (a pose from the future, a clock set
/// back, counts as fresh).
SavedPoses freshPoses(const SavedPoses& poses, std::int64_t nowUnixMs, double maxAgeS);

/// When to write: at most once every `periodMs` of the caller's clock.
class PoseWriter {
 public:
  PoseWriter(std::string path, std::int64_t periodMs) : path_(std::move(path)), periodMs_(periodMs) {}
  [[nodiscard]] bool enabled() const { return !path_.empty(); }
  [[nodiscard]] bool due(std::int64_t nowMs) const {
    return enabled() && (last_ < 0 || nowMs - last_ >= periodMs_);
  }
  /// Writes (`now` the caller's clock) and remembers when; a failure is returned for the caller to
  /// log (the next is tried a period later all the same).
  Expected<void> write(const SavedPoses& poses, std::int64_t nowMs) {
    last_ = nowMs;
    return writePoseFile(path_, poses);
  }

 private:
  std::string path_;
  std::int64_t periodMs_;
  std::int64_t last_ = -1;
};

}  // namespace fleet::agent
