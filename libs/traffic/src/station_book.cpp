#include "fleet/traffic/station_book.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <stdexcept>
#include <string>

namespace fleet::traffic {

StationBook::StationBook(const RoadmapTravel& roads, const std::vector<NodeId>& docks, double dwell,
                         std::size_t slots)
    : roads_(roads), index_(roads.roadmap().graph.size(), -1) {
  for (const auto& s : roads.roadmap().stations) {
    if (s.dock == kNoNode || std::find(docks.begin(), docks.end(), s.dock) == docks.end() ||
        index_[static_cast<std::size_t>(s.dock)] >= 0) {
      continue;
    }
    index_[static_cast<std::size_t>(s.dock)] = static_cast<int>(lines_.size());
    lines_.push_back(
        {s.name, dwell + roads.dockMoveSeconds(s.name), slots > 0 ? slots : roads.lineCapacity(s.name), {}});
  }
}

const StationBook::Line& StationBook::at(NodeId dock) const {
  const int i = dock >= 0 && static_cast<std::size_t>(dock) < index_.size()
                    ? index_[static_cast<std::size_t>(dock)]
                    : -1;
  if (i < 0) {
    throw std::out_of_range("station book: node " + std::to_string(dock) + " is no served station's dock");
  }
  return lines_[static_cast<std::size_t>(i)];
}

StationBook::Line& StationBook::at(NodeId dock) {
  return const_cast<Line&>(static_cast<const StationBook&>(*this).at(dock));
}

double StationBook::travel(NodeId from, NodeId dock) const {
  return roads_.fromNode(from, at(dock).name).value_or(std::numeric_limits<double>::infinity());
}

void StationBook::clear() {
  for (auto& l : lines_) {
    l.arrivals.clear();
  }
}

std::size_t StationBook::book(NodeId dock, double arrival) {
  auto& a = at(dock).arrivals;
  a.push_back(arrival);
  return a.size() - 1;
}

double StationBook::leave(NodeId dock, std::size_t booking) const {
  const Line& l = at(dock);
  // Served in arrival order (booking order among equal arrivals), from now on.
  std::vector<std::size_t> order(l.arrivals.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t x, std::size_t y) { return l.arrivals[x] < l.arrivals[y]; });
  double free = 0.0;
  for (std::size_t i : order) {
    if (!std::isfinite(l.arrivals[i])) {
      continue;
    }
    free = std::max(std::max(l.arrivals[i], 0.0), free) + l.cycle;
    if (i == booking) {
      return free;
    }
  }
  return std::numeric_limits<double>::infinity();
}

SlotOffer StationBook::offer(NodeId dock, double arrival) const {
  const Line& l = at(dock);
  return offerSlot(l.arrivals, arrival, l.cycle, l.slots);
}

}  // namespace fleet::traffic
