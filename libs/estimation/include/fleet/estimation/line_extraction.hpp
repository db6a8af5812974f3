#pragma once

#include <cstddef>
#include <span>
#include <vector>

#include "fleet/core/expected.hpp"
#include "fleet/core/vec2.hpp"
#include "fleet/estimation/pose_ekf.hpp"

namespace fleet::estimation {

/// One planar laser scan in the robot frame: beam i points at angle_min + i·angle_increment,
/// counter-clockwise from the robot's x axis (the scanner is assumed at the robot's axle midpoint).
/// Ranges outside [rangeMin, range_max] or non-finite are "no return".
struct LaserScan {
  double angle_min = 0.0;
  double angle_increment = 0.0;
  double rangeMin = 0.4;  ///< SICK LRF of seed 003: 0.4–80 m
  double range_max = 80.0;
  std::vector<double> ranges;
};

/// Total-least-squares line through points (eq. 3.31: minimises Σ (x cos ψ + y sin ψ − r)²) with its
/// first-order covariance for isotropic point noise σ (the thesis's "equal Cartesian error" assumption).
struct LineFit {
  double r = 0.0;
  double psi = 0.0;
  double varR = 0.0;
  double varPsi = 0.0;
  double covRPsi = 0.0;
  double rmsResidual = 0.0;
};
/// Needs at least 2 distinct points.
Expected<LineFit> fitLine(std::span<const Vec2> points, double pointSigma);

struct LineExtractionParams {
  std::size_t seedPoints = 8;    ///< N_L: consecutive points a segment starts from
  double maxThreshold = 0.05;    ///< disT_max [m]: a seed whose points stray further is no line
  double minThreshold = 0.02;    ///< floor of the per-segment (dynamic) threshold [m]
  double thresholdFactor = 3.0;  ///< per-segment threshold = factor × seed RMS residual, clamped
  std::size_t maxMisses = 2;     ///< consecutive off-line points that end a segment
  double maxPointGap = 0.5;      ///< a jump this large [m] between accepted points ends a segment
  std::size_t minPoints = 12;
  double minLength = 0.3;    ///< [m]
  double pointSigma = 0.01;  ///< isotropic point noise for the line covariance [m]

  [[nodiscard]] Expected<void> validate() const;
};

struct ExtractedLine {
  LineObservation line;  ///< r, ψ in the robot frame with varR, varPsi, covRPsi
  Vec2 first;            ///< segment end points (robot frame)
  Vec2 last;
  std::size_t points = 0;
};

/// Sequential region-growing extraction of seed 003 §3.1.2: fit N_L consecutive points; if they lie
/// within disT_max, grow the segment with the following points that stay within its own (dynamic)
/// threshold, skipping up to maxMisses stray points; refit; repeat from the segment's end.
std::vector<ExtractedLine> extractLines(const LaserScan& scan, const LineExtractionParams& params = {});

}  // namespace fleet::estimation
