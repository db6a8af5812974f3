#include "fleet/avoidance/local_planner.hpp"

#include <string>

#include "fleet/avoidance/dynamic_window.hpp"

namespace fleet::avoidance {

Expected<std::unique_ptr<LocalPlanner>> makePlanner(std::string_view name) {
  if (name == "dwa")
    return std::unique_ptr<LocalPlanner>(std::make_unique<DynamicWindowPlanner>());
  return fleet::unexpected("unknown_planner", "no local planner named '" + std::string(name) + "'");
}

}  // namespace fleet::avoidance
