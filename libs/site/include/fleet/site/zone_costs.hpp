#pragma once

// The site's zones as cost layers of the one grid A* (planning/astar.hpp), with the roadmap's
// meaning (libs/traffic/roadmap.cpp): a one-way zone allows headings within 90° of its direction,
// a speed-limit zone makes its cells take longer. No-go zones are not costs: Site::drivable()
// blocks them.

#include <memory>

#include "fleet/planning/cost_layer.hpp"
#include "fleet/site/site.hpp"

namespace fleet::site {

/// A move whose direction runs more than 90° off the allowed heading of the cell it leaves or
/// enters costs `wrongWayFactor` times its length (soft, as the lanes: a dead end stays reachable).
class OneWayCost final : public planning::CostLayer {
 public:
  OneWayCost(std::shared_ptr<const Site> site, double wrongWayFactor)
      : site_(std::move(site)), factor_(wrongWayFactor) {}
  [[nodiscard]] double factor(planning::Cell from, planning::Cell to) const override;
  [[nodiscard]] const char* name() const override { return "one_way_zones"; }

 private:
  std::shared_ptr<const Site> site_;
  double factor_;
};

/// Entering a cell limited to v below `cruise` costs cruise / v times the move's length: the path
/// cost is then travel time at cruise speed (v at least 0.05 m/s, as the roadmap's drive time).
class SpeedZoneCost final : public planning::CostLayer {
 public:
  SpeedZoneCost(std::shared_ptr<const Site> site, double cruise) : site_(std::move(site)), cruise_(cruise) {}
  [[nodiscard]] double factor(planning::Cell from, planning::Cell to) const override;
  [[nodiscard]] const char* name() const override { return "speed_zones"; }

 private:
  std::shared_ptr<const Site> site_;
  double cruise_;
};

/// The layers the site's zones call for (none for a site without one-way or speed-limit zones).
[[nodiscard]] planning::CostLayers zoneCostLayers(const std::shared_ptr<const Site>& site, double cruise,
                                                  double wrongWayFactor = 10.0);

}  // namespace fleet::site
