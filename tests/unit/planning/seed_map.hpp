#pragma once

#include <string>

#include "fleet/planning/map_io.hpp"

// Seed 004, Example 3 (Fig. 7): 12 x 12, '#' obstacle, A start, B goal; coordinates in the paper are
// 1-based (row, column) from the top-left.
inline const char* kSeed004Rows[12] = {"............", ".......#.#..", "......#..#..", "......##..B#",
                                       ".....#.#..#.", "...#........", "...#...#.##.", "..####.#....",
                                       ".....#..#.#.", ".A...##.#.##", "......#.....", "............"};

inline std::string seed004MovingAi() {
  std::string s = "type octile\nheight 12\nwidth 12\nmap\n";
  for (const char* row : kSeed004Rows) {
    for (const char* c = row; *c != '\0'; ++c) {
      s += (*c == '#') ? '@' : '.';
    }
    s += '\n';
  }
  return s;
}

// Paper (row, column) -> our cell (x right, y up).
inline fleet::planning::Cell seedCell(int row, int col) {
  return {col - 1, 12 - row};
}
