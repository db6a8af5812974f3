#include "robot_time.hpp"

namespace fleet::wms {

void RobotTimeLedger::onState(const msg::RobotState& s) {
  auto it = last_.find(s.robot_id);
  if (it == last_.end()) {
    if (last_.size() >= kMaxRobots) {
      return;
    }
    last_[s.robot_id] = {s.stamp_ns, msg::activityOf(s)};
    robots_[s.robot_id];  // listed from its first sample, with nothing filed yet
    return;
  }
  Last& l = it->second;
  const std::int64_t gap = s.stamp_ns - l.stampNs;
  if (gap <= 0) {
    return;  // a sample as old as or older than the last one (delivered late): nothing to file
  }
  if (gap <= kMaxGapNs) {
    robots_[s.robot_id].add(l.activity, static_cast<double>(gap) * 1e-9);
  }
  l = {s.stamp_ns, msg::activityOf(s)};
}

ActivityLedger RobotTimeLedger::fleet() const {
  ActivityLedger all;
  for (const auto& [id, l] : robots_) {
    all.add(l);
  }
  return all;
}

}  // namespace fleet::wms
