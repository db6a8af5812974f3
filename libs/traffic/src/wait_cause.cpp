#include "fleet/traffic/wait_cause.hpp"

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

}  // namespace fleet::traffic
