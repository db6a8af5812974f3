#include "fleet/fleet/robot_registry.hpp"

#include <algorithm>
#include <cmath>

namespace fleet {

std::int64_t leaseFromRate(double rateHz, double missed) {
  if (!(rateHz > 0.0) || !(missed > 0.0)) {
    return 0;
  }
  return static_cast<std::int64_t>(std::llround(missed / rateHz * 1e9));
}

RobotRegistry::Update RobotRegistry::observe(const RobotObservation& o) {
  auto it = robots_.find(o.id);
  if (it == robots_.end()) {
    RobotInfo r;
    r.id = o.id;
    r.pose = o.pose;
    r.battery = o.battery;
    r.lastSeenNs = o.stampNs;
    r.fault = o.fault;
    robots_.emplace(o.id, std::move(r));
    return Update::New;
  }
  RobotInfo& r = it->second;
  if (o.stampNs < r.lastSeenNs) {
    return Update::Stale;
  }
  r.pose = o.pose;
  r.battery = o.battery;
  r.lastSeenNs = o.stampNs;
  r.fault = o.fault;
  if (r.lost) {
    r.lost = false;
    r.taskId.clear();
    return Update::Recovered;
  }
  return Update::Updated;
}

std::vector<RobotInfo> RobotRegistry::expire(std::int64_t nowNs) {
  std::vector<RobotInfo> out;
  for (auto& [id, r] : robots_) {
    if (!r.lost && nowNs - r.lastSeenNs > leaseNs_) {
      r.lost = true;
      out.push_back(r);
    }
  }
  return out;
}

bool RobotRegistry::markLost(std::string_view id) {
  auto it = robots_.find(id);
  if (it == robots_.end() || it->second.lost) {
    return false;
  }
  it->second.lost = true;
  return true;
}

void RobotRegistry::expect(std::string_view id, std::int64_t nowNs) {
  auto it = robots_.find(id);
  if (it == robots_.end()) {
    RobotInfo r;
    r.id = std::string(id);
    r.lastSeenNs = nowNs;
    robots_.emplace(std::string(id), std::move(r));
  } else {
    it->second.lastSeenNs = std::max(it->second.lastSeenNs, nowNs);
  }
}

bool RobotRegistry::setTask(std::string_view id, std::string taskId) {
  auto it = robots_.find(id);
  if (it == robots_.end()) {
    return false;
  }
  it->second.taskId = std::move(taskId);
  return true;
}

bool RobotRegistry::clearTask(std::string_view id) {
  return setTask(id, {});
}

const RobotInfo* RobotRegistry::find(std::string_view id) const {
  auto it = robots_.find(id);
  return it == robots_.end() ? nullptr : &it->second;
}

std::vector<RobotInfo> RobotRegistry::idleRobots() const {
  std::vector<RobotInfo> out;
  for (const auto& [id, r] : robots_) {
    if (r.idle()) {
      out.push_back(r);
    }
  }
  return out;
}

std::vector<RobotInfo> RobotRegistry::all() const {
  std::vector<RobotInfo> out;
  out.reserve(robots_.size());
  for (const auto& [id, r] : robots_) {
    out.push_back(r);
  }
  return out;
}

std::size_t RobotRegistry::onlineCount() const {
  return static_cast<std::size_t>(
      std::count_if(robots_.begin(), robots_.end(), [](const auto& kv) { return !kv.second.lost; }));
}

}  // namespace fleet
