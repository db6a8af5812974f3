#include "gateway.hpp"

#include "event_log.hpp"

#include <algorithm>
#include <limits>
#include <nlohmann/json.hpp>

namespace fleet::wms {
namespace {
constexpr std::size_t kEventBuffer = 10'000;
bool terminal(msg::TaskState s) {
  return s == msg::TaskState::Done || s == msg::TaskState::Failed || s == msg::TaskState::Cancelled;
}
/// The task JSON `body` with the priority and deadline a change event carries (0: left out, as
/// toJson leaves out a default).
void applyChange(std::string& body, const msg::TaskEvent& e) {
  auto j = nlohmann::json::parse(body, nullptr, false);
  if (!j.is_object()) {
    return;
  }
  for (const auto& [key, value] :
       {std::pair{"priority", std::int64_t{e.priority}}, std::pair{"deadline_ns", e.deadline_ns}}) {
    if (value != 0) {
      j[key] = value;
    } else {
      j.erase(key);
    }
  }
  body = j.dump();
}
}  // namespace

void FleetView::setEventLog(EventLog* log) {
  std::lock_guard lock(logMutex_);
  log_ = log;
}

void FleetView::dropEventLog(const EventLog* log) {
  std::lock_guard lock(logMutex_);
  if (log_ == log) {
    log_ = nullptr;
  }
}

std::uint64_t FleetView::staleEpochEvents() const {
  std::lock_guard lock(logMutex_);
  return static_cast<std::uint64_t>(managerEpoch_.dropped());
}

std::string FleetView::eventLogProblem() const {
  std::lock_guard lock(logMutex_);
  return logProblem_;
}

void FleetView::onEvent(const msg::TaskEvent& e) {
  onEvents({e});
}

void FleetView::onEvents(const std::vector<msg::TaskEvent>& all) {
  std::vector<msg::TaskEvent> events;
  {
    std::lock_guard lock(logMutex_);
    for (const auto& e : all) {
      if (managerEpoch_.admit(e.epoch)) {
        events.push_back(e);
      }
    }
  }
  for (const auto& e : events) {
    viewEvent(e);
  }
  std::lock_guard lock(logMutex_);
  if (log_ == nullptr || events.empty()) {
    return;
  }
  try {
    log_->append(events, std::chrono::duration_cast<std::chrono::nanoseconds>(
                             std::chrono::system_clock::now().time_since_epoch())
                             .count());
  } catch (const std::exception& ex) {
    // A full or broken disk: the view and the dashboard go on, /v1/metrics shows the count.
    ++logFailures_;
    logProblem_ = ex.what();
  }
}

void FleetView::catchUp(const std::vector<msg::TaskEvent>& events) {
  for (const auto& e : events) {
    {
      std::lock_guard lock(m_);
      const auto it = tasks_.find(e.task_id);
      if (it != tasks_.end() && it->second.seq >= e.seq) {
        continue;  // heard already, or a newer one
      }
    }
    viewEvent(e);
  }
}

void FleetView::viewEvent(const msg::TaskEvent& e) {
  {
    std::lock_guard lock(m_);
    auto [it, inserted] = tasks_.try_emplace(e.task_id);
    auto& v = it->second;
    if (inserted) {
      v.id = e.task_id;
      insertion_.push_back(e.task_id);
    }
    // Events may arrive twice (transient-local history to a late joiner) or out of order across
    // restarts of the manager: keep the newest by sequence, then by time.
    if (inserted || e.seq > v.seq || (e.seq == v.seq && e.stamp_ns >= v.updatedNs)) {
      v.state = e.state;
      v.robot = e.robot_id;
      v.reason = e.reason;
      v.updatedNs = e.stamp_ns;
      v.seq = e.seq;
      v.station = e.station;
      v.etaNs = e.eta_ns;
      v.step = e.step;
      if (e.changed && !v.body.empty()) {
        applyChange(v.body, e);
      }
    }
    events_.push_back(e);
    ++eventCount_;
    if (events_.size() > kEventBuffer) {
      events_.pop_front();
    }
    // Bound memory: forget the oldest finished tasks first.
    while (tasks_.size() > maxTasks_ && !insertion_.empty()) {
      const std::string old = insertion_.front();
      insertion_.pop_front();
      auto o = tasks_.find(old);
      if (o != tasks_.end() && terminal(o->second.state)) {
        tasks_.erase(o);
      } else if (o != tasks_.end()) {
        insertion_.push_back(old);
        if (insertion_.size() > 2 * maxTasks_) {
          break;
        }
      }
    }
  }
  cv_.notify_all();
}

void FleetView::onAccepted(const std::string& id, const std::string& body, msg::TaskState state,
                           std::int64_t nowNs) {
  std::lock_guard lock(m_);
  auto [it, inserted] = tasks_.try_emplace(id);
  if (inserted) {
    it->second.id = id;
    it->second.state = state;
    it->second.updatedNs = nowNs;
    insertion_.push_back(id);
  }
  it->second.body = body;
}

void FleetView::onStored(const msg::TaskAck& a, std::int64_t nowNs) {
  const auto d = nlohmann::json::parse(a.detail, nullptr, false);
  std::lock_guard lock(m_);
  auto [it, inserted] = tasks_.try_emplace(a.task_id);
  auto& v = it->second;
  if (!inserted) {
    return;  // an event came while the query was out: it is at least as new
  }
  v.id = a.task_id;
  insertion_.push_back(a.task_id);
  v.state = a.state;
  v.updatedNs = nowNs;
  if (d.is_object()) {
    v.robot = d.value("robot", "");
    v.reason = d.value("reason", "");
    v.updatedNs = d.value("updated_ns", nowNs);
    v.seq = d.value("revision", 0U);
    if (d.contains("task")) {
      v.body = d["task"].dump();
      if (d.value("station_chosen", false) && d["task"].is_object()) {
        v.station = d["task"].value("station", "");
      }
    }
  }
}

void FleetView::onRobot(const msg::RobotState& s) {
  std::lock_guard lock(m_);
  robots_[s.robot_id] = s;
  robotTime_.onState(s);
}

RobotTimeLedger FleetView::robotTime() const {
  std::lock_guard lock(m_);
  return robotTime_;
}

bool FleetView::onPeopleSeen(msg::PeopleSeen p, std::int64_t receivedNs) {
  std::lock_guard lock(m_);
  if (!robots_.contains(p.robot_id)) {
    rejections_.count({"PeopleSeen", "unknown_robot",
                       "robot_id \"" + p.robot_id + "\" is no robot this adapter has a state of"});
    return false;
  }
  auto& s = people_[p.robot_id];
  if (s.people.stamp_ns > p.stamp_ns && s.receivedNs + kPeopleSeenMaxAgeNs > receivedNs) {
    return true;  // older than the list kept (delivered late): keep the newer one
  }
  s = {std::move(p), receivedNs};
  return true;
}

bool FleetView::fresh(const Seen& s, std::int64_t nowNs) const {
  if (nowNs - s.receivedNs > kPeopleSeenMaxAgeNs) {
    return false;
  }
  const auto r = robots_.find(s.people.robot_id);
  return r != robots_.end() && r->second.stamp_ns - s.people.stamp_ns <= kPeopleSeenMaxAgeNs;
}

std::optional<msg::PeopleSeen> FleetView::peopleSeen(const std::string& robot, std::int64_t nowNs) const {
  std::lock_guard lock(m_);
  const auto it = people_.find(robot);
  if (it == people_.end() || !fresh(it->second, nowNs)) {
    return std::nullopt;
  }
  return it->second.people;
}

std::map<std::string, msg::PeopleSeen> FleetView::allPeopleSeen(std::int64_t nowNs) const {
  std::lock_guard lock(m_);
  std::map<std::string, msg::PeopleSeen> out;
  for (const auto& [robot, s] : people_) {
    if (fresh(s, nowNs)) {
      out.emplace(robot, s.people);
    }
  }
  return out;
}

void FleetView::updateProximity(std::int64_t nowNs) {
  std::vector<ProximityDisc> robots;
  std::vector<ProximityDisc> people;
  {
    std::lock_guard lock(m_);
    std::int64_t newest = std::numeric_limits<std::int64_t>::min();
    for (const auto& [id, r] : robots_) {
      newest = std::max(newest, r.stamp_ns);
    }
    for (const auto& [id, r] : robots_) {
      if (newest - r.stamp_ns <= kLiveRobotNs) {
        robots.push_back({id, r.pose.position(), static_cast<double>(r.radius)});
      }
    }
    for (const auto& [robot, s] : people_) {
      if (fresh(s, nowNs)) {
        for (const auto& p : s.people.people) {
          people.push_back(
              {"", {static_cast<double>(p.x), static_cast<double>(p.y)}, static_cast<double>(p.r)});
        }
      }
    }
  }
  std::lock_guard lock(proximityMutex_);
  proximity_.update(robots, people);
}

FleetView::Proximity FleetView::proximity() const {
  std::lock_guard lock(proximityMutex_);
  return {proximity_.robotRobot(), proximity_.robotPerson(), proximity_.params(), proximity_.version()};
}

void FleetView::onRisk(msg::RiskMap m) {
  auto shared = std::make_shared<const msg::RiskMap>(std::move(m));
  std::lock_guard lock(m_);
  risk_ = std::move(shared);
  ++riskCount_;
}

std::pair<std::uint64_t, std::shared_ptr<const msg::RiskMap>> FleetView::risk() const {
  std::lock_guard lock(m_);
  return {riskCount_, risk_};
}

void FleetView::onRoadmap(msg::Roadmap m) {
  auto shared = std::make_shared<const msg::Roadmap>(std::move(m));
  std::lock_guard lock(m_);
  std::erase_if(releases_, [&](const auto& kv) { return kv.second->epoch < shared->epoch; });
  roadmap_ = std::move(shared);
  ++roadmapCount_;
  ++releaseCount_;
}

void FleetView::onClosure(const msg::TrafficClosure& c) {
  std::lock_guard lock(m_);
  if (c.active) {
    closures_[c.closure_id] = c;
  } else {
    closures_.erase(c.closure_id);
  }
}

std::map<std::string, msg::TrafficClosure> FleetView::closures() const {
  std::lock_guard lock(m_);
  return closures_;
}

void FleetView::onRelease(const msg::TrafficRelease& r) {
  auto shared = std::make_shared<const msg::TrafficRelease>(r);
  std::lock_guard lock(m_);
  if (roadmap_ && r.epoch < roadmap_->epoch) {
    return;  // a previous traffic manager's, delivered late
  }
  auto it = releases_.find(r.robot_id);
  if (it == releases_.end()) {
    if (releases_.size() >= kMaxReleaseRobots) {
      return;
    }
    releases_.emplace(r.robot_id, std::move(shared));
  } else if (r.epoch >= it->second->epoch) {
    it->second = std::move(shared);
  } else {
    return;
  }
  ++releaseCount_;
}

std::pair<std::uint64_t, std::shared_ptr<const msg::Roadmap>> FleetView::roadmap() const {
  std::lock_guard lock(m_);
  return {roadmapCount_, roadmap_};
}

std::pair<std::uint64_t, FleetView::Releases> FleetView::releases() const {
  std::lock_guard lock(m_);
  return {releaseCount_, releases_};
}

std::optional<TaskView> FleetView::task(const std::string& id) const {
  std::lock_guard lock(m_);
  auto it = tasks_.find(id);
  if (it == tasks_.end()) {
    return std::nullopt;
  }
  return it->second;
}

std::vector<TaskView> FleetView::tasks(std::optional<msg::TaskState> state, std::size_t limit) const {
  std::lock_guard lock(m_);
  std::vector<TaskView> out;
  for (const auto& [id, v] : tasks_) {
    if (out.size() >= limit) {
      break;
    }
    if (!state || v.state == *state) {
      out.push_back(v);
    }
  }
  return out;
}

std::vector<msg::RobotState> FleetView::robots() const {
  std::lock_guard lock(m_);
  std::vector<msg::RobotState> out;
  for (const auto& [id, r] : robots_) {
    out.push_back(r);
  }
  return out;
}

std::map<std::string, std::int64_t> FleetView::countByState() const {
  std::lock_guard lock(m_);
  std::map<std::string, std::int64_t> out;
  for (const auto& [id, v] : tasks_) {
    ++out[msg::toString(v.state)];
  }
  return out;
}

std::uint64_t FleetView::eventsAfter(std::uint64_t cursor, std::chrono::milliseconds timeout,
                                     std::vector<msg::TaskEvent>& out) const {
  std::unique_lock lock(m_);
  cv_.wait_for(lock, timeout, [&] { return eventCount_ > cursor; });
  const std::uint64_t first = eventCount_ - events_.size();
  for (std::uint64_t i = std::max(cursor, first); i < eventCount_; ++i) {
    out.push_back(events_[static_cast<std::size_t>(i - first)]);
  }
  return eventCount_;
}

std::uint64_t FleetView::eventCursor() const {
  std::lock_guard lock(m_);
  return eventCount_;
}

}  // namespace fleet::wms
