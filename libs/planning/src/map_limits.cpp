#include "fleet/planning/map_limits.hpp"

#include <cmath>
#include <sstream>

namespace fleet::planning {

namespace {

std::string num(double v) {
  std::ostringstream os;
  os.precision(6);
  os << v;
  return os.str();
}

std::string keyed(const std::string& source, const std::string& key) {
  const std::string head = source.empty() ? "" : source + ": ";
  return key.empty() ? head : head + key + ": ";
}

}  // namespace

Expected<void> checkMapSize(double width, double height, double resolution, Vec2 origin,
                            const std::string& source, const std::string& sizeKey,
                            const std::string& resolutionKey, const std::string& originKey) {
  if (!(std::isfinite(resolution) && resolution > 0.0)) {
    return unexpected("map_size",
                      keyed(source, resolutionKey) + num(resolution) + " is not a positive number");
  }
  if (resolution < kMinMapResolution) {
    return unexpected("map_size", keyed(source, resolutionKey) + num(resolution) +
                                      " m per cell is finer than the limit of " + num(kMinMapResolution) +
                                      " m (a 1 m robot would span " + num(1.0 / resolution) + " cells)");
  }
  const double cells = width * height;
  if (!(width >= 1.0 && height >= 1.0 && cells <= kMaxMapCells)) {
    return unexpected("map_size", keyed(source, sizeKey) + num(width) + " x " + num(height) +
                                      " makes the map " + num(cells) + " cells (limit " +
                                      std::to_string(static_cast<long long>(kMaxMapCells)) + " = 2^26)");
  }
  const double w = width * resolution;
  const double h = height * resolution;
  if (!(w <= kMaxMapSideM && h <= kMaxMapSideM)) {
    return unexpected("map_size", keyed(source, resolutionKey) + num(resolution) +
                                      " m per cell makes the map " + num(w) + " x " + num(h) + " m (limit " +
                                      num(kMaxMapSideM) + " m a side)");
  }
  if (!(std::abs(origin.x) <= kMaxMapOriginM && std::abs(origin.y) <= kMaxMapOriginM)) {
    return unexpected("map_size", keyed(source, originKey) + "(" + num(origin.x) + ", " + num(origin.y) +
                                      ") puts the map more than " + num(kMaxMapOriginM) +
                                      " m from the map frame's origin (limit)");
  }
  return {};
}

}  // namespace fleet::planning
