#include "fleet/traffic/wait_cause.hpp"

#include <algorithm>

namespace fleet::traffic {

const char* toString(WaitCause c) {
  switch (c) {
    case WaitCause::SameWay:
      return "same_way";
    case WaitCause::HeadOn:
      return "head_on";
    case WaitCause::Across:
      return "across";
    case WaitCause::Standing:
      return "standing";
    case WaitCause::Dwelling:
      return "dwelling";
    case WaitCause::NoneNamed:
      return "none_named";
  }
  return "none_named";
}

WaitCause classifyWait(const WaitSeen& s) {
  if (!s.named)
    return WaitCause::NoneNamed;
  if (s.otherDwelling)
    return WaitCause::Dwelling;
  const double otherLength = s.otherWay.norm();
  if (!s.otherDriving || otherLength <= 0.0)
    return WaitCause::Standing;
  Vec2 way = s.way;
  if (way.norm() <= 0.0)
    way = s.otherAt - s.at;  // no next node: the way towards the robot it waits on
  const double length = way.norm();
  if (length <= 0.0)
    return WaitCause::Across;  // on top of each other (never, with conflicts kept): no way to compare
  const double cosine = way.dot(s.otherWay) / (length * otherLength);
  // 60°: a lattice's edges meet at multiples of 45°, so a way one bend off (45°, 135°) falls
  // clearly on one side, never on the line.
  constexpr double kCos60 = 0.5;
  if (cosine > kCos60)
    return WaitCause::SameWay;
  if (cosine < -kCos60)
    return WaitCause::HeadOn;
  return WaitCause::Across;
}

WaitSeen waitSeen(const Graph& g, const std::vector<WaitSnapshot>& robots, std::size_t r,
                  const Release& release) {
  const WaitSnapshot& me = robots.at(r);
  WaitSeen seen;
  seen.at = g.position(me.at);
  const auto& base = release.base;
  const auto it = std::find(base.begin(), base.end(), me.at);
  const NodeId next = it != base.end() && it + 1 != base.end() ? *(it + 1)
                      : !release.horizon.empty()               ? release.horizon.front()
                                                               : kNoNode;
  if (next != kNoNode)
    seen.way = g.position(next) - seen.at;
  seen.named = me.on < robots.size();
  if (seen.named) {
    const WaitSnapshot& q = robots[me.on];
    seen.otherAt = g.position(q.at);
    seen.otherDriving = q.to != kNoNode;
    if (seen.otherDriving)
      seen.otherWay = g.position(q.to) - g.position(q.at);
    seen.otherDwelling = q.dwelling;
  }
  return seen;
}

}  // namespace fleet::traffic
