#include "dds_gateway.hpp"

#include <spdlog/spdlog.h>

#include "fleet/validation/sample_checks.hpp"

namespace fleet::wms {

DdsGateway::DdsGateway(transport::Participant& p, FleetView& view)
    : view_(view), tasks_(p), acks_(p), events_(p), robots_(p), ws_(p) {
  ws_.attach(acks_);
  ws_.attach(events_);
  ws_.attach(robots_);
  try {
    risk_ = std::make_unique<transport::Reader<msg::RiskMap>>(p);
    ws_.attach(*risk_);
  } catch (const std::exception& e) {
    spdlog::warn("wms adapter: no risk map for the dashboard ({})", e.what());
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

void DdsGateway::loop() {
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
    for (auto& e : events_.take()) {
      if (validation::admit(e, view_.rejections())) {
        view_.onEvent(e);
      }
    }
    for (auto& r : robots_.take()) {
      if (validation::admit(r, view_.rejections())) {
        view_.onRobot(r);
      }
    }
    auto maps = risk_ ? risk_->take() : std::vector<msg::RiskMap>{};
    if (!maps.empty() && validation::admit(maps.back(), view_.rejections())) {
      view_.onRisk(std::move(maps.back()));  // only the newest matters
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
