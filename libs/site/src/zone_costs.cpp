#include "fleet/site/zone_costs.hpp"

#include <algorithm>
#include <cmath>

namespace fleet::site {

double OneWayCost::factor(planning::Cell from, planning::Cell to) const {
  const auto& oneWay = site_->layers.oneWay;
  const auto& map = site_->map;
  if (oneWay.size() != map.size()) {
    return 1.0;
  }
  const Vec2 dir{static_cast<double>(to.x - from.x), static_cast<double>(to.y - from.y)};
  for (const planning::Cell c : {from, to}) {
    if (!map.inside(c)) {
      continue;
    }
    const float phi = oneWay[map.index(c)];
    if (std::isfinite(phi) &&
        dir.dot({static_cast<double>(std::cos(phi)), static_cast<double>(std::sin(phi))}) < -1e-9) {
      return factor_;
    }
  }
  return 1.0;
}

double SpeedZoneCost::factor(planning::Cell /*from*/, planning::Cell to) const {
  const auto& limit = site_->layers.speedLimit;
  const auto& map = site_->map;
  if (limit.size() != map.size() || !map.inside(to)) {
    return 1.0;
  }
  const double v = static_cast<double>(limit[map.index(to)]);
  return v < cruise_ ? cruise_ / std::max(0.05, v) : 1.0;
}

planning::CostLayers zoneCostLayers(const std::shared_ptr<const Site>& site, double cruise,
                                    double wrongWayFactor) {
  planning::CostLayers out;
  if (!site) {
    return out;
  }
  const auto& l = site->layers;
  if (std::any_of(l.oneWay.begin(), l.oneWay.end(), [](float v) { return std::isfinite(v); })) {
    out.push_back(std::make_shared<OneWayCost>(site, wrongWayFactor));
  }
  if (std::any_of(l.speedLimit.begin(), l.speedLimit.end(),
                  [cruise](float v) { return static_cast<double>(v) < cruise; })) {
    out.push_back(std::make_shared<SpeedZoneCost>(site, cruise));
  }
  return out;
}

}  // namespace fleet::site
