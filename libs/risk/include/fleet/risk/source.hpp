#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "fleet/core/expected.hpp"
#include "fleet/risk/disc.hpp"
#include "fleet/risk/reference_algorithm.hpp"

namespace fleet::risk {

/// One PredictedDiscs sample: disc k is the source's predicted disc at t0_ns + k·dt.
struct Source {
  std::string id;
  SourceKind kind = SourceKind::kRobot;
  std::int64_t t0_ns = 0;
  double dt = 0.1;  // seconds between discs
  std::vector<Disc> discs;
};

/// Bounds a sample must respect to be accepted (bad samples are dropped, never fused).
struct SourceLimits {
  std::size_t maxSteps = 200;
  double maxRadius = 5.0;                    // m; a warehouse robot or person is well below this
  double maxSigma = 10.0;                    // m
  double maxAbsCoordinate = 1e5;             // m from the map origin
  double maxDt = 10.0;                       // s
  std::int64_t maxFutureNs = 5'000'000'000;  // t0 may lead `now` by at most this much
};

/// Error codes: "invalid_id", "empty", "too_many_steps", "bad_dt", "non_finite", "bad_radius",
/// "bad_sigma", "non_finite_covariance", "bad_covariance" (not positive semi-definite, or a major-axis
/// σ above maxSigma), "out_of_range", "future_timestamp". The message names the disc index and value.
/// The timestamp check runs only when nowNs is given.
Expected<void> validateSource(const Source& source, const SourceLimits& limits,
                              std::optional<std::int64_t> nowNs = std::nullopt);

/// Common time base of a fusion: step k is at tRefNs + k·dt.
struct TimeBase {
  std::int64_t tRefNs = 0;
  double dt = 0.1;
  int steps = 30;
  bool operator==(const TimeBase&) const = default;
};

/// The source's disc at each step of the time base, linearly interpolated (x, y, r, sigma, covariance)
/// between its samples. Steps before t0 or after the last sample by more than half a source step are empty
/// (no prediction there); within that half step the end disc is held. A one-disc source is a snapshot
/// held over the whole horizon.
AlignedSource alignSource(const Source& source, const TimeBase& base);

}  // namespace fleet::risk
