#include "fleet/core/station_slots.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

namespace fleet {

SlotOffer offerSlot(std::span<const double> arrivals, double arrival, double cycle, std::size_t slots) {
  std::vector<double> a;
  a.reserve(arrivals.size() + 1);
  for (double t : arrivals) {
    if (std::isfinite(t)) {
      a.push_back(std::max(t, 0.0));
    }
  }
  std::sort(a.begin(), a.end());
  const double mine = std::max(arrival, 0.0);
  // After every robot arriving at the same moment: those are already bound for the station.
  const auto at = static_cast<std::size_t>(std::upper_bound(a.begin(), a.end(), mine) - a.begin());
  a.insert(a.begin() + static_cast<std::ptrdiff_t>(at), mine);
  std::vector<double> leave(a.size());
  double free = 0.0;
  SlotOffer offer;
  for (std::size_t i = 0; i < a.size(); ++i) {
    const double start = std::max(a[i], free);
    leave[i] = free = start + cycle;
    if (i == at) {
      offer.wait = start - a[i];
      offer.leave = leave[i];
    }
  }
  offer.admitted = true;
  if (slots == 0) {
    return offer;
  }
  for (std::size_t j = at; j < a.size() && offer.admitted; ++j) {
    // In the line at a[j]: every robot arrived by then (i <= j) and not yet served.
    std::size_t inLine = 0;
    for (std::size_t i = 0; i <= j; ++i) {
      inLine += leave[i] > a[j] ? 1 : 0;
    }
    offer.admitted = inLine <= slots;
  }
  return offer;
}

}  // namespace fleet
