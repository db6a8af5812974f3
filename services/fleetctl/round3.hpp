#pragma once

// Figures written to a run's JSON files are rounded to three decimals (ms, mm, ‰ of a share):
// enough for every figure we report, and files that diff cleanly between runs.

#include <cmath>

namespace fleet::ctl {

inline double round3(double x) {
  return std::round(x * 1000.0) / 1000.0;
}

}  // namespace fleet::ctl
