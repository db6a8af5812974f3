#pragma once

// Sensor readings to what the robot knows of itself and its surroundings: the pose estimate (EKF on
// wheel odometry, compass, laser lines matched to the site's walls and landmark bearings, in the
// order of seed 003), the scan and the detections in the map frame, the people tracked from reading
// to reading, and whether the reading stream has been lost.

#include <cstdint>
#include <memory>
#include <optional>
#include <utility>
#include <vector>

#include "fleet/core/pose2.hpp"
#include "fleet/estimation/line_extraction.hpp"
#include "fleet/estimation/line_matching.hpp"
#include "fleet/estimation/pose_ekf.hpp"
#include "wheel_totals.hpp"

namespace fleet::agent {

enum class SeenKind { kRobot, kHuman };

/// One sensor reading as the robot's driver sends it (robot frame, the sensor's precision).
struct SensorReading {
  struct Sighting {
    SeenKind kind = SeenKind::kRobot;
    float x = 0;  ///< robot frame [m]
    float y = 0;
    float r = 0;  ///< radius [m]
  };
  std::int64_t stampNs = 0;
  double dsLeft = 0;  ///< wheel travel since the previous reading sent [m]
  double dsRight = 0;
  bool wheelTotalsValid = false;  ///< the totals below are set (older drivers leave them out)
  double wheelLeftTotal = 0;      ///< [m] since the driver started
  double wheelRightTotal = 0;
  std::uint64_t driverSession = 0;  ///< the driver's run the totals count in (0: not told)
  bool compassValid = false;
  double compass = 0;
  std::vector<std::pair<std::int32_t, float>> bearings;  ///< landmark id, bearing [rad]
  float angleMin = 0;  ///< the range scan: ray i at angleMin + i · angleIncrement
  float angleIncrement = 0;
  float rangeMax = 0;  ///< a range not below this is no return
  std::vector<float> ranges;
  std::vector<Sighting> sightings;
};

/// A scan ray with a return, in the robot frame and in the map frame.
struct ScanRay {
  double range = 0.0;
  Vec2 local;
  Vec2 map;
};

/// Something the sensor recognised (a robot or a person), in the robot frame and in the map frame.
struct Detection {
  SeenKind kind = SeenKind::kRobot;
  Vec2 local;
  double radius = 0.0;
  Vec2 map;
};

/// A person seen in the latest reading (map frame) with a velocity from the reading before: a
/// person walking across the robot's way is outside the corridor the stop rule watches until too
/// late.
struct Person {
  Vec2 pos;
  Vec2 velocity;
  double radius = 0.25;
  bool tracked = false;  ///< seen in the reading before too: `velocity` is measured (else zero)
};

/// What the robot knows as of the latest reading.
struct Perception {
  bool valid = false;  ///< a reading has arrived (else the lists are empty)
  Pose2 pose;
  std::vector<ScanRay> scan;  ///< in the sensor's ray order
  std::vector<Detection> detections;
  std::vector<Person> people;

  /// The scan's points closer than maxRange, in the map frame.
  [[nodiscard]] std::vector<Vec2> scanPoints(double maxRange) const;
};

/// The stream watch's answer for one cycle.
struct StreamCheck {
  enum class Change { kNone, kLost, kBack };
  bool lost = false;  ///< no reading for longer than the timeout
  Change change = Change::kNone;
  double silentS = 0.0;       ///< on kLost: how long no reading has come
  std::int64_t outageNs = 0;  ///< on kBack: how long the stream was lost
};

/// Line extraction tuned for the simulator's scanner (72 rays over 360°, 5° apart, σ 1 cm): a 1 m
/// shelf end 2 m away gives 6 points, so the seed and the minimum are small.
estimation::LineExtractionParams agentLineExtraction();

/// How uncertain a pose the localization resumes from is (a robot restarted where it was):
/// variances of (0.7 m)² and (0.5 rad)². A robot rolls on after its process stops (its last
/// command for the driver's 0.5 s timeout, then braking: ~0.7 m from cruise, up to ~0.9 rad
/// turning) and the pose was written up to 0.2 s before; the compass and the lines must not be
/// gated out (a 0.45 rad heading error against 0.1 rad was, and the robot stayed lost).
constexpr double kResumeVarianceXY = 0.49;
constexpr double kResumeVarianceTheta = 0.25;
/// ... and with the driver's wheel totals kept beside the pose: the roll since is known exactly,
/// what is left is the saved estimate's own error, variances of (0.1 m)² and (0.1 rad)². The wide
/// variances above let a line match a shelf face one row (2.5 m) off: a robot resumed 1.2 m
/// behind where it stood localized on the wrong row and drove into the shelf's side.
constexpr double kResumeWheelsVarianceXY = 0.01;
constexpr double kResumeWheelsVarianceTheta = 0.01;
/// A wheel's travel between the kept totals and the first reading after a resume above this is no
/// roll (the driver restarted and counts from zero, or it is another one): not used, the start
/// covariance is widened to the kResumeVariance* ones.
constexpr double kResumeRollMaxM = 2.0;

struct LocalizerParams {
  Pose2 start;
  double startVarianceXY = 0.01;      ///< m², the start pose's variance in x and in y
  double startVarianceTheta = 0.001;  ///< rad²
  /// The driver's wheel totals at `start` (a robot resumed from the pose file): the first reading's
  /// totals give the motion since. Checked against kResumeRollMaxM.
  std::optional<WheelTotals> startWheels;
  double wheelBase = 0.4;
  double sensorTimeoutS = 0.5;  ///< no reading for this long (of the cycle clock): the stream is lost
  /// How far the robot may have rolled unseen in a gap (its last command held, then braking).
  double vMax = 0.8;
  double wMax = 1.5;
  double accelMax = 1.0;
  double alphaMax = 3.0;
  std::vector<std::pair<std::int32_t, Vec2>> landmarks;
  /// The site's wall faces (site::wallSegments), shared by every robot of a process. Null or empty:
  /// no line updates.
  std::shared_ptr<const std::vector<estimation::MapSegment>> walls;
  bool lineUpdates = true;  ///< false: odometry, compass and bearings only (the comparison runs)
  estimation::LineExtractionParams lines = agentLineExtraction();
  estimation::LineGate lineGate;
  /// Added to each fitted line's variances: what the fit does not know of (a scan point on a corner
  /// or on someone in front of the wall, the map's cells against the real faces).
  double lineRangeSigma = 0.01;  ///< m
  double lineAngleSigma = 0.01;  ///< rad
};

/// Why the line updates of a reading did or did not happen, cumulative. Every extracted line ends
/// in exactly one of matched (then accepted or rejectedByFilter), noWallFacing, outsideGate,
/// noOverlap or ambiguous.
struct LineStats {
  std::uint64_t scans = 0;         ///< readings with a scan looked at
  std::uint64_t scansNoLines = 0;  ///< ... in which no line was found ("no_lines")
  std::uint64_t extracted = 0;
  std::uint64_t matched = 0;
  std::uint64_t accepted = 0;
  std::uint64_t rejectedByFilter = 0;  ///< matched, then refused by the EKF's own gate after earlier updates
  std::uint64_t noWallFacing = 0;      ///< "noWallFacing"
  std::uint64_t outsideGate = 0;       ///< "outsideGate"
  std::uint64_t noOverlap = 0;         ///< "noOverlap"
  std::uint64_t ambiguous = 0;         ///< "ambiguous"
};

/// The corrections one reading went through, in the order they ran.
enum class Update { kOdometry, kCompass, kLine, kBearing };

class Localizer {
 public:
  explicit Localizer(LocalizerParams params);

  void onReading(const SensorReading& r);
  /// Once per cycle, before anything uses the perception: tracks reading arrival against the
  /// cycle clock (the first call starts the count: a robot that never gets a reading is lost too).
  StreamCheck checkStream(std::int64_t nowNs);

  [[nodiscard]] const Perception& perception() const { return seen_; }
  [[nodiscard]] Pose2 pose() const { return ekf_.pose(); }
  [[nodiscard]] const Eigen::Matrix3d& covariance() const { return ekf_.covariance(); }
  [[nodiscard]] bool lost() const { return lost_; }
  /// The estimate is finite and inside the world (|x|, |y| within validation::kMaxCoordinate, the
  /// covariance finite). False for good once the EKF has been fed motion no robot makes.
  [[nodiscard]] bool plausible() const;
  /// EKF updates refused (outliers, bad input), cumulative.
  [[nodiscard]] std::uint64_t rejected() const { return rejected_; }
  [[nodiscard]] const LineStats& lineStats() const { return lineStats_; }
  /// Of the latest reading (one entry per correction tried, accepted or not).
  [[nodiscard]] const std::vector<Update>& lastUpdates() const { return updates_; }
  /// The driver's wheel totals of the reading the estimate is as of (none before the first
  /// reading with totals, or from a driver that does not send them).
  [[nodiscard]] std::optional<WheelTotals> wheelTotals() const;
  /// Wheel totals kept over a restart that did not fit the first reading (kResumeRollMaxM).
  [[nodiscard]] bool resumeTotalsRefused() const { return resumeTotalsRefused_; }
  /// Readings whose driver session differed from the one before (the driver restarted under a
  /// running agent): the motion of that interval is the reading's own increment, not the totals'.
  [[nodiscard]] std::uint64_t driverRestarts() const { return driverRestarts_; }

 private:
  void track(const SensorReading& r);
  void updateLines(const SensorReading& r);

  LocalizerParams p_;
  estimation::PoseEkf ekf_;
  Perception seen_;
  std::int64_t lastStampNs_ = 0;  // stamp of the previous reading (valid once seen_.valid)
  bool haveTotals_ = false;       // the previous reading had wheel totals
  double wheelLeft_ = 0.0;        // ... these
  double wheelRight_ = 0.0;
  std::uint64_t session_ = 0;  // ... and the driver's run they count in
  std::uint64_t driverRestarts_ = 0;
  bool checkResumeRoll_ = false;  // the totals above were kept over a restart, not yet checked
  bool resumeTotalsRefused_ = false;
  std::int64_t peopleStampNs_ = -1;
  std::uint64_t rejected_ = 0;
  LineStats lineStats_;
  std::vector<Update> updates_;

  bool readingSinceCheck_ = false;
  std::int64_t lastReadingNs_ = -1;  // cycle time at which the latest reading was seen
  bool lost_ = false;
  std::int64_t lostSinceNs_ = 0;
};

}  // namespace fleet::agent
