#include "base_end.hpp"

namespace fleet::agent {

BaseEnd baseEnd(double left, Vec2 toEnd, Vec2 facing, bool finalApproach, const BaseEndParams& p) {
  const double off = toEnd.norm();
  if (left < p.atEnd) {
    return off > p.settleBeyond ? BaseEnd::kSettle : BaseEnd::kStand;
  }
  if (finalApproach && off < p.behindWithin && toEnd.dot(facing) < p.atEnd) {
    return BaseEnd::kStand;
  }
  return BaseEnd::kDrive;
}

}  // namespace fleet::agent
