#pragma once

#include <cstddef>
#include <vector>

#include "fleet/control/lyapunov_pose_controller.hpp"
#include "fleet/control/twist.hpp"
#include "fleet/core/expected.hpp"
#include "fleet/core/pose2.hpp"
#include "fleet/core/vec2.hpp"

namespace fleet::control {

struct PathFollowerParams {
  /// Arc length [m] ahead of the robot's projection on the path at which the carrot is placed.
  double lookahead = 0.6;
  /// Projection search window [m] past the current progress; keeps a path that crosses itself from
  /// snapping to a later pass.
  double searchWindow = 2.0;
  /// Final-pose controller (the two-region law by default). Tracking uses the same gains with the
  /// single far-field law and no reversing, since the carrot always lies ahead on the path.
  LyapunovParams controller;
  double goalToleranceXy = 0.02;       ///< [m]
  double goalToleranceTheta = 0.0087;  ///< [rad] (0.5°)

  [[nodiscard]] Expected<void> validate() const;
};

struct PathFollowerOutput {
  Twist cmd;
  Pose2 target;                ///< carrot (or the final pose on the last stretch)
  bool finalApproach = false;  ///< the carrot reached the end; the final pose controller is in charge
  bool goalReached = false;    ///< within the goal tolerances (cmd is then zero)
  double progress = 0.0;       ///< arc length of the robot's projection on the path [m]
  double crossTrack = 0.0;     ///< distance from the robot to the path [m]
};

/// Follows a polyline with the Lyapunov controller: each step projects the robot on the path (progress
/// never goes back), places a carrot `lookahead` further along, and steers to it with the far-field
/// law using the path tangent as the carrot's heading. When the carrot reaches the path's end the
/// final pose is handed to the two-region controller.
class PathFollower {
 public:
  explicit PathFollower(PathFollowerParams params = {});

  /// Waypoints with the final heading taken from `poses.back().theta`; intermediate headings are
  /// ignored (the tangent is used). Consecutive duplicates are dropped. Errors: empty, non-finite.
  Expected<void> setPath(const std::vector<Pose2>& poses);
  Expected<void> setPath(const std::vector<Vec2>& points, double final_heading);

  /// Error "no_path" before setPath, "non_finite_pose" for a NaN/inf estimate.
  Expected<PathFollowerOutput> step(const Pose2& estimate);

  [[nodiscard]] bool hasPath() const { return !points_.empty(); }
  [[nodiscard]] double pathLength() const { return cumulative_.empty() ? 0.0 : cumulative_.back(); }

 private:
  [[nodiscard]] Pose2 pointAt(double s) const;

  PathFollowerParams params_;
  LyapunovPoseController tracker_;
  LyapunovPoseController final_;
  std::vector<Vec2> points_;
  std::vector<double> cumulative_;
  double final_heading_ = 0.0;
  double progress_ = 0.0;
  std::size_t segment_ = 0;
};

}  // namespace fleet::control
