#include "proximity_counter.hpp"

#include <algorithm>
#include <cmath>

namespace fleet::wms {
namespace {

/// Indices of `discs` ordered by x (the sweep below looks only at neighbours in x).
std::vector<std::size_t> byX(const std::vector<ProximityDisc>& discs) {
  std::vector<std::size_t> order(discs.size());
  for (std::size_t i = 0; i < order.size(); ++i) {
    order[i] = i;
  }
  std::sort(order.begin(), order.end(),
            [&](std::size_t a, std::size_t b) { return discs[a].at.x < discs[b].at.x; });
  return order;
}

double largestRadius(const std::vector<ProximityDisc>& discs) {
  double r = 0.0;
  for (const auto& d : discs) {
    r = std::max(r, d.radius);
  }
  return r;
}

bool usable(const ProximityDisc& d) {
  return std::isfinite(d.at.x) && std::isfinite(d.at.y) && std::isfinite(d.radius) && d.radius >= 0.0;
}

}  // namespace

void ProximityCounter::step(PairState& s, double c, ProximityCounts& counts) const {
  if (!s.close && c < p_.nearMissMargin) {
    s.close = true;
    ++counts.nearMisses;
  } else if (s.close && c >= p_.nearMissMargin + p_.hysteresis) {
    s.close = false;
  }
  if (!s.contact && c < 0.0) {
    s.contact = true;
    ++counts.contacts;
  } else if (s.contact && c >= p_.hysteresis) {
    s.contact = false;
  }
  counts.close += s.close ? 1 : 0;
  counts.inContact += s.contact ? 1 : 0;
}

void ProximityCounter::update(const std::vector<ProximityDisc>& robotsIn,
                              const std::vector<ProximityDisc>& peopleIn) {
  const ProximityCounts beforeR = robots_;
  const ProximityCounts beforeP = people_;
  // A pair's state matters up to this clearance; beyond it every pair is in no state.
  const double watch = p_.nearMissMargin + p_.hysteresis;

  std::vector<ProximityDisc> robots;
  std::set<std::string> ids;
  for (const auto& r : robotsIn) {
    if (usable(r) && ids.insert(r.id).second) {
      robots.push_back(r);
    }
  }
  std::vector<ProximityDisc> people;
  for (const auto& p : peopleIn) {
    if (usable(p)) {
      people.push_back(p);
    }
  }

  // Robot-robot: a sweep in x; the window shrinks to the closest clearance found so far (never
  // below what the states need), so the minimum is exact without looking at every pair.
  robots_.close = 0;
  robots_.inContact = 0;
  std::map<std::pair<std::string, std::string>, PairState> pairs;
  double best = std::numeric_limits<double>::infinity();
  const auto order = byX(robots);
  const double twoR = 2.0 * largestRadius(robots);
  for (std::size_t a = 0; a < order.size(); ++a) {
    const auto& i = robots[order[a]];
    for (std::size_t b = a + 1; b < order.size(); ++b) {
      const auto& j = robots[order[b]];
      if (j.at.x - i.at.x > twoR + std::max(watch, best)) {
        break;
      }
      const double c = distance(i.at, j.at) - i.radius - j.radius;
      best = std::min(best, c);
      if (c < watch) {
        auto key = i.id < j.id ? std::make_pair(i.id, j.id) : std::make_pair(j.id, i.id);
        PairState s = robotPairs_.contains(key) ? robotPairs_[key] : PairState{};
        step(s, c, robots_);
        if (s.close || s.contact) {
          pairs.emplace(std::move(key), s);
        }
      }
    }
  }
  robotPairs_ = std::move(pairs);  // pairs not within `watch` have left every state
  robots_.minClearance = std::min(robots_.minClearance, best);

  // Robot-person: each robot with its nearest person (people are sorted by x, looked up in a window).
  people_.close = 0;
  people_.inContact = 0;
  std::map<std::string, PairState> near;
  best = std::numeric_limits<double>::infinity();
  const auto porder = byX(people);
  const double pr = largestRadius(people);
  for (const auto& r : robots) {
    double nearest = std::numeric_limits<double>::infinity();
    const double window = r.radius + pr + std::max(watch, best);
    auto first = std::lower_bound(porder.begin(), porder.end(), r.at.x - window,
                                  [&](std::size_t k, double x) { return people[k].at.x < x; });
    for (auto it = first; it != porder.end() && people[*it].at.x <= r.at.x + window; ++it) {
      nearest = std::min(nearest, distance(r.at, people[*it].at) - r.radius - people[*it].radius);
    }
    best = std::min(best, nearest);
    if (nearest < watch) {
      PairState s = personPairs_.contains(r.id) ? personPairs_[r.id] : PairState{};
      step(s, nearest, people_);
      if (s.close || s.contact) {
        near.emplace(r.id, s);
      }
    }
  }
  personPairs_ = std::move(near);
  people_.minClearance = std::min(people_.minClearance, best);

  auto same = [](const ProximityCounts& a, const ProximityCounts& b) {
    return a.contacts == b.contacts && a.nearMisses == b.nearMisses && a.inContact == b.inContact &&
           a.close == b.close && a.minClearance == b.minClearance;
  };
  if (!same(beforeR, robots_) || !same(beforeP, people_)) {
    ++version_;
  }
}

}  // namespace fleet::wms
