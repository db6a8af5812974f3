#pragma once

// Admission by predicted arrival (docs/algorithms.md, "Admission by predicted arrival"). A station
// is a first-come first-served server: it takes `cycle` seconds a robot (its least dock cycle:
// enter from the queue head, dwell, leave) and its line holds `slots` robots at once (the dock and
// its queue places). The robots bound for it are known by their predicted arrival, in seconds from
// now (0 or less: there now). In arrival order each is served from s_i = max(a_i, e_{i-1}) and
// leaves the line at e_i = s_i + cycle. A new robot arriving at `arrival` is given a slot when,
// with it added, the line holds at most `slots` robots at its arrival and at every arrival after
// it; its expected wait is s − a. A robot that will get there after the line has cleared takes no
// slot now: a robot two minutes away does not keep the station from robots that will be there
// sooner, which counting robots by the station they are bound for did.
//
// Pure; O(k²) for k robots bound for the station (a handful: the line holds them).

#include <cstddef>
#include <span>

namespace fleet {

struct SlotOffer {
  bool admitted = false;
  double wait = 0.0;   ///< s from its arrival until its service starts (queue wait)
  double leave = 0.0;  ///< s from now until it leaves the line, served
};

/// The slot a robot arriving in `arrival` s would get. `slots` 0: no limit (always admitted).
/// Arrivals need no order; a non-finite one (a robot with no way there) is left out.
[[nodiscard]] SlotOffer offerSlot(std::span<const double> arrivals, double arrival, double cycle,
                                  std::size_t slots);

}  // namespace fleet
