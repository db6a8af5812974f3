#include "dds_gateway.hpp"

#include <spdlog/spdlog.h>

#include "fleet/validation/sample_checks.hpp"

namespace fleet::wms {

namespace {

/// A reader the dashboard wants but the adapter can do without: DDS permissions made before the
/// dashboard (scripts/dds-security) do not let the adapter read these topics.
template <class T>
void optionalReader(transport::Participant& p, transport::WaitSet& ws,
                    std::unique_ptr<transport::Reader<T>>& out, const char* what) {
  try {
    out = std::make_unique<transport::Reader<T>>(p);
    ws.attach(*out);
  } catch (const std::exception& e) {
    spdlog::warn("wms adapter: no {} for the dashboard ({})", what, e.what());
  }
}

/// Counts the samples a per-robot reader dropped since the last call (a writer outside the
/// partition of the robot they name: robot_partition.hpp) as `topic`:foreign_robot.
void countForeign(validation::Rejections& into, const char* topic, std::uint64_t total,
                  std::uint64_t& counted) {
  for (; counted < total; ++counted) {
    into.count({topic, "foreign_robot", "a writer outside the partition of the robot the sample names"});
  }
}

}  // namespace

DdsGateway::DdsGateway(transport::Participant& p, FleetView& view)
    : view_(view), tasks_(p), acks_(p), events_(p), robots_(p), ws_(p) {
  ws_.attach(acks_);
  ws_.attach(events_);
  ws_.attach(robots_);
  optionalReader(p, ws_, risk_, "risk map");
  optionalReader(p, ws_, roadmap_, "roadmap");
  optionalReader(p, ws_, releases_, "traffic releases");
  optionalReader(p, ws_, people_, "people seen");
  optionalReader(p, ws_, closuresIn_, "roadmap closures");
  try {
    closuresOut_ = std::make_unique<transport::Writer<msg::TrafficClosure>>(p);
  } catch (const std::exception& e) {
    spdlog::warn("wms adapter: roadmap closures cannot be sent ({})", e.what());
  }
  thread_ = std::thread([this] { loop(); });
}

DdsGateway::~DdsGateway() {
  stop_ = true;
  ws_.wake();
  thread_.join();
}

bool DdsGateway::managerOnline() const {
  return tasks_.matchedReaders() > 0;
}

std::optional<std::string> DdsGateway::sendClosure(const msg::TrafficClosure& c) {
  if (!closuresOut_) {
    return std::string("this adapter may not write TrafficClosure (DDS permissions)");
  }
  try {
    // Under the lock, so a PUT and a DELETE of one id at once leave the view as the topic has it.
    std::lock_guard lock(writeMutex_);
    closuresOut_->write(c);
    view_.onClosure(c);  // at once, not only when the sample comes back
  } catch (const std::exception& e) {
    return std::string("TrafficClosure not sent: ") + e.what();
  }
  return std::nullopt;
}

bool DdsGateway::trafficManagerOnline() const {
  return closuresOut_ && closuresOut_->matchedReaders() > 0;
}

void DdsGateway::loop() {
  // Contacts and near misses are looked for at most this often (the loop wakes with every sample).
  constexpr auto kProximityPeriod = std::chrono::milliseconds(50);
  auto proximityAt = std::chrono::steady_clock::now() - kProximityPeriod;
  while (!stop_) {
    ws_.wait(std::chrono::milliseconds(200));
    auto acks = acks_.take();
    if (!acks.empty()) {
      std::lock_guard lock(m_);
      for (auto& a : acks) {
        if (!validation::admit(a, view_.rejections())) {
          continue;  // its request times out (503, retry)
        }
        auto it = pending_.find(a.request_id);
        if (it != pending_.end()) {
          it->second = std::move(a);
        }
      }
      cv_.notify_all();
    }
    std::vector<msg::TaskEvent> admitted;
    for (auto& e : events_.take()) {
      if (validation::admit(e, view_.rejections())) {
        admitted.push_back(std::move(e));
      }
    }
    view_.onEvents(admitted);
    for (auto& r : robots_.take()) {
      if (validation::admit(r, view_.rejections())) {
        view_.onRobot(r);
      }
    }
    countForeign(view_.rejections(), "RobotState", robots_.foreign(), foreignStates_);
    // After the states: the first list of a robot whose first state came with it is not refused.
    for (auto& p : people_ ? people_->take() : std::vector<msg::PeopleSeen>{}) {
      if (validation::admit(p, view_.rejections())) {
        view_.onPeopleSeen(std::move(p), steadyNowNs());
      }
    }
    if (people_) {
      countForeign(view_.rejections(), "PeopleSeen", people_->foreign(), foreignPeople_);
    }
    if (const auto now = std::chrono::steady_clock::now(); now - proximityAt >= kProximityPeriod) {
      proximityAt = now;
      view_.updateProximity(steadyNowNs());
    }
    auto maps = risk_ ? risk_->take() : std::vector<msg::RiskMap>{};
    if (!maps.empty() && validation::admit(maps.back(), view_.rejections())) {
      view_.onRisk(std::move(maps.back()));  // only the newest matters
    }
    auto roadmaps = roadmap_ ? roadmap_->take() : std::vector<msg::Roadmap>{};
    if (!roadmaps.empty() && validation::admit(roadmaps.back(), view_.rejections())) {
      view_.onRoadmap(std::move(roadmaps.back()));
    }
    for (auto& c : closuresIn_ ? closuresIn_->take() : std::vector<msg::TrafficClosure>{}) {
      if (validation::admit(c, view_.rejections())) {
        view_.onClosure(c);
      }
    }
    for (auto& r : releases_ ? releases_->take() : std::vector<msg::TrafficRelease>{}) {
      if (validation::admit(r, view_.rejections())) {
        view_.onRelease(r);
      }
    }
  }
}

std::vector<std::optional<msg::TaskAck>> DdsGateway::submit(const std::vector<msg::Task>& requests,
                                                            std::chrono::milliseconds timeout) {
  {
    std::lock_guard lock(m_);
    for (const auto& r : requests) {
      pending_[r.request_id] = std::nullopt;
    }
  }
  {
    std::lock_guard lock(writeMutex_);
    for (const auto& r : requests) {
      tasks_.write(r);
    }
  }
  std::vector<std::optional<msg::TaskAck>> out;
  std::unique_lock lock(m_);
  cv_.wait_for(lock, timeout, [&] {
    for (const auto& r : requests) {
      if (!pending_[r.request_id]) {
        return false;
      }
    }
    return true;
  });
  for (const auto& r : requests) {
    out.push_back(std::move(pending_[r.request_id]));
    pending_.erase(r.request_id);
  }
  lock.unlock();
  std::lock_guard wlock(writeMutex_);
  for (const auto& r : requests) {
    tasks_.unregister(r);  // the writer need not remember one instance per task ever seen
  }
  return out;
}

}  // namespace fleet::wms
