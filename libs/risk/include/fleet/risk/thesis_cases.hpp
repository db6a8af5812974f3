#pragma once

#include <string>
#include <vector>

#include "fleet/risk/grid.hpp"
#include "fleet/risk/reference_algorithm.hpp"

namespace fleet::risk {

/// One computed case of seed 000 §3.3 (Tables 3.1 and 3.2). The thesis prints K, R1, R2, T and N but
/// not the trajectories or the window; ours are documented per case in thesis_cases.cpp and
/// docs/algorithms.md. Units are the thesis's (abstract length units, time steps of 1).
struct ThesisCase {
  std::string name;                    // e.g. "table3_1_case1"
  std::string description;             // the trajectories in words
  std::vector<int> levels;             // the K values the thesis shows
  bool complement = false;             // Table 3.2 cases show 1 − P
  GridSpec grid;                       // N + 1 points per axis, x_i = i·h, h = xmax / N
  std::vector<AlignedSource> sources;  // discs at t = 0, 1, …, T
};

std::vector<ThesisCase> thesisCases();

}  // namespace fleet::risk
