#pragma once

// How far each robot's own pose estimate (the RobotState it publishes) is from where the simulator
// has it: position and heading error over time, for the localization figures (docs/benchmarks.md).

#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "fleet/core/pose2.hpp"

namespace fleet::sim {

class LocalizationErrorLog {
 public:
  /// `binS`: the series holds one point per bin of simulated time (mean and max over robots and
  /// samples in it); `hidden`: the stretches [from, to) in simulated s in which landmarks were hidden.
  explicit LocalizationErrorLog(double binS = 1.0, std::vector<std::pair<double, double>> hidden = {});

  /// The true poses of the robots at simulated time `tNs` (the instant a SensorFrame stamped `tNs`
  /// was taken). The last kHistory instants are kept.
  void truth(std::int64_t tNs, const std::vector<Pose2>& poses);
  /// A robot's estimate stamped `stampNs`: compared with the truth of the same instant. An estimate
  /// of an instant no longer (or not yet) held is counted, not compared.
  void estimate(std::size_t robot, std::int64_t stampNs, const Pose2& est);

  [[nodiscard]] std::size_t samples() const { return samples_; }
  [[nodiscard]] std::size_t unmatched() const { return unmatched_; }
  /// {"bin_s", "hidden": [[from, to]...], "series": [{"t", "pos_mean", "pos_max", "head_mean",
  /// "head_max", "hidden"}...], "overall"/"hidden_stretches"/"visible_stretches": {"samples",
  /// "pos_rmse", "pos_p95", "pos_max", "head_rmse", "head_p95", "head_max"}, "per_robot":
  /// [{"robot", "pos_max", "pos_max_t", "pos_last", "head_max"}...], "unmatched"}. `names`: the
  /// robots' ids by index (else the index).
  [[nodiscard]] nlohmann::json toJson(const std::vector<std::string>& names = {}) const;

  static constexpr std::size_t kHistory = 32;

 private:
  [[nodiscard]] bool hiddenAt(double t) const;

  struct Bin {
    double posSum = 0.0;
    double posMax = 0.0;
    double headSum = 0.0;
    double headMax = 0.0;
    std::size_t n = 0;
  };
  double binS_;
  std::vector<std::pair<double, double>> hidden_;
  std::vector<std::pair<std::int64_t, std::vector<Pose2>>> history_;  // ring of kHistory instants
  std::size_t next_ = 0;
  std::vector<Bin> bins_;
  struct Robot {
    double posMax = 0.0;
    double posMaxT = 0.0;
    double posLast = 0.0;
    double headMax = 0.0;
    bool seen = false;
  };
  std::vector<Robot> robots_;
  // Per sample, for the percentiles: position error [m], |heading error| [rad], hidden.
  std::vector<float> pos_;
  std::vector<float> head_;
  std::vector<bool> inHidden_;
  std::size_t samples_ = 0;
  std::size_t unmatched_ = 0;
};

}  // namespace fleet::sim
