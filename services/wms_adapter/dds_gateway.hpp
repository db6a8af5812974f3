#pragma once

#include <atomic>
#include <memory>
#include <thread>
#include <unordered_map>

#include "fleet/transport/dds.hpp"
#include "gateway.hpp"

namespace fleet::wms {

/// TaskGateway over DDS: writes Task requests, matches TaskAcks to waiting requests, and feeds the
/// FleetView from TaskEvent and RobotState (and, for the dashboard, RiskMap, Roadmap and
/// TrafficRelease) on a background thread.
class DdsGateway final : public TaskGateway {
 public:
  DdsGateway(transport::Participant& p, FleetView& view);
  ~DdsGateway() override;
  DdsGateway(const DdsGateway&) = delete;
  DdsGateway& operator=(const DdsGateway&) = delete;

  std::vector<std::optional<msg::TaskAck>> submit(const std::vector<msg::Task>& requests,
                                                  std::chrono::milliseconds timeout) override;
  [[nodiscard]] bool managerOnline() const override;
  std::optional<std::string> sendClosure(const msg::TrafficClosure& c) override;
  [[nodiscard]] bool trafficManagerOnline() const override;

 private:
  void loop();

  FleetView& view_;
  transport::Writer<msg::Task> tasks_;
  transport::Reader<msg::TaskAck> acks_;
  transport::Reader<msg::TaskEvent> events_;
  transport::Reader<msg::RobotState> robots_;
  // For the dashboard's iso-level layer; none where the DDS permissions (made before the dashboard)
  // do not let the adapter read RiskMap: the adapter runs on without the layer.
  std::unique_ptr<transport::Reader<msg::RiskMap>> risk_;
  // The traffic layer (roadmap, releases), likewise optional; only read, never written.
  std::unique_ptr<transport::Reader<msg::Roadmap>> roadmap_;
  std::unique_ptr<transport::Reader<msg::TrafficRelease>> releases_;
  // The people the robots see (robot agents publish them), likewise optional.
  std::unique_ptr<transport::Reader<msg::PeopleSeen>> people_;
  // Roadmap closures operators make through the API (written) and every adapter's (read, so the
  // list shows them all); optional as the rest of the traffic layer.
  std::unique_ptr<transport::Writer<msg::TrafficClosure>> closuresOut_;
  std::unique_ptr<transport::Reader<msg::TrafficClosure>> closuresIn_;
  std::uint64_t foreignStates_ = 0;  // robots_/people_ foreign samples counted so far (loop thread)
  std::uint64_t foreignPeople_ = 0;
  transport::WaitSet ws_;
  std::mutex writeMutex_;
  std::mutex m_;
  std::condition_variable cv_;
  std::unordered_map<std::string, std::optional<msg::TaskAck>> pending_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

}  // namespace fleet::wms
