#include "people_report.hpp"

#include <algorithm>

namespace fleet::agent {

std::optional<msg::PeopleSeen> PeopleReport::due(const std::string& robot, std::int64_t nowNs,
                                                 const Perception& seen, bool sensorLost) {
  if (nextNs_ < 0) {
    nextNs_ = nowNs + phaseNs_;
  }
  if (nowNs < nextNs_ || !seen.valid || sensorLost) {
    return std::nullopt;
  }
  // From the due time, not from now: the rate stays the period's whatever the cycle length.
  nextNs_ += periodNs_ * (1 + (nowNs - nextNs_) / periodNs_);
  std::vector<Person> people = seen.people;
  if (people.size() > msg::kMaxPeopleSeen) {
    const Vec2 at = seen.pose.position();
    std::partial_sort(
        people.begin(), people.begin() + static_cast<std::ptrdiff_t>(msg::kMaxPeopleSeen), people.end(),
        [&](const Person& a, const Person& b) { return distance(a.pos, at) < distance(b.pos, at); });
    people.resize(msg::kMaxPeopleSeen);
  }
  msg::PeopleSeen out;
  out.robot_id = robot;
  out.stamp_ns = nowNs;
  out.people.reserve(people.size());
  for (const auto& p : people) {
    out.people.push_back({static_cast<float>(p.pos.x), static_cast<float>(p.pos.y),
                          static_cast<float>(p.velocity.x), static_cast<float>(p.velocity.y),
                          static_cast<float>(p.radius), p.tracked});
  }
  return out;
}

}  // namespace fleet::agent
