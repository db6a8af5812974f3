#pragma once

#include <vector>

#include "fleet/avoidance/local_planner.hpp"

namespace fleet::avoidance {

/// Objective G = wHeading·heading + wClearance·clearance + wVelocity·velocity
///             + wProgress·progress − wRisk·risk, each term normalised to [0, 1].
struct DwaParams {
  int vSamples = 20;                  ///< Nav2 DWB vx_samples
  int omegaSamples = 20;              ///< Nav2 DWB vtheta_samples
  double simTime = 1.7;               ///< rollout horizon [s] (Nav2 DWB simTime)
  double wHeading = 0.8;              ///< end-pose heading towards the carrot (Fox et al.'s "heading")
  double wClearance = 0.3;            ///< surface clearance along the rollout, saturated at clearanceCap
  double wVelocity = 0.3;             ///< forward speed / vMax
  double wProgress = 1.0;             ///< decrease of the distance to the carrot over the rollout
  double wRisk = 1.0;                 ///< max collision probability along the rollout (RiskLookup)
  double clearanceCap = 1.0;          ///< [m]
  double clearanceLength = 2.0;       ///< arc length of the clearance term's extended arc [m]
  double curvatureSpeedFloor = 0.25;  ///< curvature of a slow sample = ω / max(|v|, floor·vMax)
  double minClearance = 0.10;         ///< rollouts closer than this to anything are inadmissible [m]
  double lookahead = 1.5;             ///< carrot distance along the path [m]
  int riskSamples = 4;                ///< risk lookups per rollout (evenly spaced, end included)
  int discSamples = 8;                ///< time samples for the moving-disc check per rollout
  bool allowReverse = false;
  /// Local-minimum escape: after stuckCycles cycles without getting closer to the carrot by
  /// stuckProgress, drop the heading and progress terms for escapeCycles cycles, so the robot
  /// follows the most open arc (clearance + speed) around what blocks it.
  int stuckCycles = 15;
  double stuckProgress = 0.05;  ///< [m]
  int escapeCycles = 25;
  /// Evaluate samples in decreasing order of their score bound and stop once none can beat the
  /// best (same choice as the exhaustive loop, which `prune = false` runs: the cross-check).
  bool prune = true;

  [[nodiscard]] Expected<void> validate() const;
};

/// Score of one sampled velocity; exposed for tests and the benchmark.
struct DwaSample {
  Twist twist;
  double heading = 0.0;
  double clearance = 0.0;
  double velocity = 0.0;
  double progress = 0.0;
  double risk = 0.0;
  double score = 0.0;
  bool admissible = false;
  /// False when pruning skipped the expensive terms (clearance, risk, score and admissible are
  /// then not computed): its bound showed it could not beat the chosen sample.
  bool evaluated = false;
};

/// The positions at t = duration k / count, k = 1..count, of a robot leaving `start` with the
/// constant twist `tw` (exact circular arcs, as DiffDriveKinematics::integrateExact), into `out`.
void arcPoints(const Pose2& start, Twist tw, double duration, int count, std::vector<Vec2>& out);

/// Pick the carrot: the point `lookahead` along the path from the path point nearest the robot.
Vec2 carrotOnPath(std::span<const Vec2> path, Vec2 robot, double lookahead);

class DynamicWindowPlanner final : public LocalPlanner {
 public:
  explicit DynamicWindowPlanner(DwaParams params = {}) : params_(params) {}
  Command plan(const LocalView& view) override;
  [[nodiscard]] std::string_view name() const override { return "dwa"; }

  /// All samples of the last plan() (admissible or not).
  [[nodiscard]] const std::vector<DwaSample>& lastSamples() const { return samples_; }
  [[nodiscard]] const DwaParams& params() const { return params_; }
  [[nodiscard]] bool escaping() const { return escape_left_ > 0; }
  void reset() override {
    no_progress_ = 0;
    escape_left_ = 0;
    best_carrot_distance_ = 0.0;
  }

 private:
  DwaParams params_;
  std::vector<DwaSample> samples_;
  std::vector<Vec2> near_;
  std::vector<MovingDisc> near_discs_;  ///< the discs a rollout can come within clearanceCap of
  std::vector<Vec2> arc_;               ///< the rollout's points at the disc check's times
  std::vector<double> upper_;
  std::vector<double> disc_clr_;
  std::vector<std::size_t> order_;
  double best_carrot_distance_ = 0.0;
  int no_progress_ = 0;
  int escape_left_ = 0;
  Vec2 last_goal_;
};

}  // namespace fleet::avoidance
