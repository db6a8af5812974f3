#include "fleet/planning/lane_map.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <numbers>
#include <queue>
#include <string>

namespace fleet::planning {

LaneMap LaneMap::derive(const OccupancyGrid& raw, const LaneParams& p) {
  LaneMap m;
  m.width_ = raw.width();
  m.height_ = raw.height();
  m.factor_ = std::max(1.0, p.wrong_way_factor);
  m.dir_.assign(raw.size(), LaneDir{});
  const int w = raw.width();
  const int h = raw.height();
  // Free runs through every cell along x and along y: length and first cell.
  std::vector<int> hrun(raw.size(), 0), hstart(raw.size(), 0), vrun(raw.size(), 0), vstart(raw.size(), 0);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w;) {
      if (raw.blocked({x, y})) {
        ++x;
        continue;
      }
      int e = x;
      while (e < w && raw.freeCell({e, y})) {
        ++e;
      }
      for (int k = x; k < e; ++k) {
        hrun[raw.index({k, y})] = e - x;
        hstart[raw.index({k, y})] = x;
      }
      x = e;
    }
  }
  for (int x = 0; x < w; ++x) {
    for (int y = 0; y < h;) {
      if (raw.blocked({x, y})) {
        ++y;
        continue;
      }
      int e = y;
      while (e < h && raw.freeCell({x, e})) {
        ++e;
      }
      for (int k = y; k < e; ++k) {
        vrun[raw.index({x, k})] = e - y;
        vstart[raw.index({x, k})] = y;
      }
      y = e;
    }
  }
  const int narrow = static_cast<int>(std::floor(p.max_aisle_width / raw.resolution() + 1e-9));
  // An aisle is named by the line of its near wall, so every segment of one aisle line (cut by
  // cross aisles) gets the same direction; neighbouring lines alternate, which gives every block
  // of shelves a loop around it.
  std::map<int, std::vector<std::size_t>> vertical;    // key: first free x across the aisle
  std::map<int, std::vector<std::size_t>> horizontal;  // key: first free y across the aisle
  for (std::size_t i = 0; i < raw.size(); ++i) {
    if (hrun[i] == 0) {
      continue;
    }
    if (hrun[i] < narrow && vrun[i] >= p.min_aspect * hrun[i]) {
      vertical[hstart[i]].push_back(i);
    } else if (vrun[i] < narrow && hrun[i] >= p.min_aspect * vrun[i]) {
      horizontal[vstart[i]].push_back(i);
    }
  }
  int k = 0;
  for (const auto& [key, cells] : vertical) {
    const auto d = static_cast<std::int8_t>(k++ % 2 == 0 ? 1 : -1);
    for (auto i : cells) {
      m.dir_[i] = {0, d};
    }
  }
  k = 0;
  for (const auto& [key, cells] : horizontal) {
    const auto d = static_cast<std::int8_t>(k++ % 2 == 0 ? 1 : -1);
    for (auto i : cells) {
      m.dir_[i] = {d, 0};
    }
  }
  // Wider corridors (the bands along the walls) get two lanes, keep right: heading +x the right
  // hand is -y, so the lower half runs +x and the upper half -x; heading +y the right hand is +x.
  // Robots meeting in a band pass side by side instead of nose to nose.
  const int twoLane = static_cast<int>(std::floor(p.max_two_lane_width / raw.resolution() + 1e-9));
  for (std::size_t i = 0; i < raw.size(); ++i) {
    if (hrun[i] == 0 || m.dir_[i] != LaneDir{}) {
      continue;
    }
    const Cell c = raw.cellOf(i);
    if (hrun[i] >= narrow && hrun[i] <= twoLane && vrun[i] >= p.min_aspect * hrun[i]) {
      const bool rightHalf = 2 * (c.x - hstart[i]) >= hrun[i];
      m.dir_[i] = {0, static_cast<std::int8_t>(rightHalf ? 1 : -1)};
    } else if (vrun[i] >= narrow && vrun[i] <= twoLane && hrun[i] >= p.min_aspect * vrun[i]) {
      const bool upperHalf = 2 * (c.y - vstart[i]) >= vrun[i];
      m.dir_[i] = {static_cast<std::int8_t>(upperHalf ? -1 : 1), 0};
    }
  }
  return m;
}

LaneDir LaneMap::at(Cell c) const {
  if (c.x < 0 || c.y < 0 || c.x >= width_ || c.y >= height_) {
    return {};
  }
  return dir_[static_cast<std::size_t>(c.y) * static_cast<std::size_t>(width_) +
              static_cast<std::size_t>(c.x)];
}

bool LaneMap::againstLane(Cell a, Cell b) const {
  const int dx = b.x - a.x;
  const int dy = b.y - a.y;
  for (const Cell c : {a, b}) {
    const LaneDir d = at(c);
    if ((d.dx != 0 && dx * d.dx < 0) || (d.dy != 0 && dy * d.dy < 0)) {
      return true;
    }
  }
  return false;
}

std::size_t LaneMap::oneWayCells() const {
  return static_cast<std::size_t>(
      std::count_if(dir_.begin(), dir_.end(), [](LaneDir d) { return d.dx != 0 || d.dy != 0; }));
}

}  // namespace fleet::planning
