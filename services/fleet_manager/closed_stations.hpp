#pragma once

// Which stations the roadmap closures in force close, for the dispatcher (Dispatcher::
// setClosedStations): a station whose dock a closure covers or cuts off from the main part of the
// roadmap. The closures are the operators' (TrafficClosure, from the WMS adapter), applied to the
// manager's own copy of the traffic manager's roadmap (the same site and `roadmap` options), as
// the traffic manager applies them. DDS-free; a part of the fleet manager with its own tests.

#include <map>
#include <optional>
#include <set>
#include <string>

#include "fleet/messages/messages.hpp"
#include "fleet/traffic/roadmap.hpp"

namespace fleet::manager {

class ClosedStations {
 public:
  explicit ClosedStations(traffic::Roadmap roadmap);

  /// Puts closure `c` in force (replacing one of the same id) or lifts it (active false). An error
  /// naming what is wrong (a node or lane not on the roadmap, nothing to close) changes nothing.
  std::optional<std::string> apply(const msg::TrafficClosure& c);
  /// Every station connected when the roadmap was built and closed now, with why: the closures in
  /// force ("closure 'spill': wet floor").
  [[nodiscard]] std::map<std::string, std::string, std::less<>> closed() const;

 private:
  struct InForce {
    std::string reason;
    std::vector<traffic::Closure> parts;
  };
  traffic::Roadmap roadmap_;
  std::set<std::string, std::less<>> connectedAtStart_;
  std::map<std::string, InForce, std::less<>> inForce_;
};

}  // namespace fleet::manager
