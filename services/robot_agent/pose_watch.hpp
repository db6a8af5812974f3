#pragma once

// Whether a robot's pose estimate can still be trusted, from what its laser lines say: a robot whose
// estimate has drifted or was seeded somewhere else (a restarted agent without its robots' poses, a
// robot carried off) sees walls where the map has none, and the localizer's gate refuses nearly every
// line it extracts. Such a robot drives its releases from the wrong place (a restarted agent's robot
// once followed its route 12 m off into a shelf corner); it must stop and say so instead.
//
// Judged over a sliding window of the localizer's cumulative line counts: doubted when at least
// `minLines` lines were extracted in the last `windowS` seconds and fewer than `doubtBelow` of them
// were fused; trusted again when over `trustAbove` were. Too few lines (open floor, a crowd round the
// robot, no walls in range) is no evidence either way: the judgement stands.

#include <cstdint>
#include <deque>
#include <string>

namespace fleet::agent {

struct PoseWatchParams {
  double windowS = 10.0;
  std::uint64_t minLines = 20;
  /// Normal driving fuses ~98 % of the lines (300 robots among 150 people, 2026-12-04); a robot 1 m
  /// or 0.3 rad off ~7 %. 5 s and 20 % stopped robots standing among parked robots, whose scan is
  /// mostly their neighbours' flanks (docs/algorithms.md, "A robot its lines call lost stops").
  double doubtBelow = 0.1;
  double trustAbove = 0.6;
};

class PoseWatch {
 public:
  enum class Change : std::uint8_t { kNone, kDoubted, kTrusted };

  explicit PoseWatch(PoseWatchParams params = {}) : p_(params) {}

  /// Once a cycle with the localizer's cumulative counts of lines extracted and fused.
  Change update(std::int64_t nowNs, std::uint64_t extracted, std::uint64_t accepted);
  [[nodiscard]] bool doubted() const { return doubted_; }
  /// Lines extracted and fused within the window as last judged.
  [[nodiscard]] std::uint64_t extracted() const { return extracted_; }
  [[nodiscard]] std::uint64_t accepted() const { return accepted_; }
  /// Times the pose was doubted, cumulative.
  [[nodiscard]] std::uint64_t doubts() const { return doubts_; }
  /// "localization doubtful: 2 of 131 laser lines matched the site's walls in the last 10.0 s".
  [[nodiscard]] std::string why() const;

 private:
  struct Sample {
    std::int64_t ns;
    std::uint64_t extracted;
    std::uint64_t accepted;
  };
  PoseWatchParams p_;
  std::deque<Sample> window_;
  bool doubted_ = false;
  std::uint64_t extracted_ = 0;
  std::uint64_t accepted_ = 0;
  std::uint64_t doubts_ = 0;
};

}  // namespace fleet::agent
