#pragma once

// One service's operations surface: its metrics registry, its health, and the ops port serving
// both. Every service names its metrics `<service>_...` (fleet_manager_, robot_agent_, ...), gets
// `<service>_rejected_samples_total{reason}` for dropped input and `fleet_build_info`, and
// `fleet_dds_matched_{readers,writers}{topic}` for the DDS endpoints it watches. Under systemd
// (Type=notify, systemd_notify.hpp) it tells the service manager READY=1 at the loop's first
// refresh(), WATCHDOG=1 once a second from refresh() when WatchdogSec= is set (so WatchdogSec= must
// be 3 s or more; the units say 30 s), and STOPPING=1 once a stop is requested (or when it is
// destroyed).

#include <chrono>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "fleet/metrics/registry.hpp"
#include "fleet/service/health.hpp"
#include "fleet/service/ops_server.hpp"

namespace fleet::service {

class ServiceOps {
 public:
  /// `service`: the metric prefix, e.g. "fleet_manager".
  explicit ServiceOps(std::string service);
  ~ServiceOps();
  ServiceOps(const ServiceOps&) = delete;
  ServiceOps& operator=(const ServiceOps&) = delete;

  [[nodiscard]] metrics::Registry& registry() { return registry_; }
  [[nodiscard]] Health& health() { return health_; }
  [[nodiscard]] const std::string& prefix() const { return service_; }

  /// Opens the ops port when asked; on failure logs one line naming the port and returns false
  /// (the caller exits 2).
  [[nodiscard]] bool start(const OpsSettings& s);
  [[nodiscard]] int port() const { return server_.port(); }

  /// `<service>_rejected_samples_total{reason}`.
  metrics::Counter& rejected(const std::string& reason);

  /// A DDS endpoint whose matched count is published as a gauge by refresh(). `count` is called on
  /// the thread calling refresh() (the service's loop), never by the scrape.
  void watchMatchedReaders(const std::string& topic, std::function<std::uint32_t()> count);
  void watchMatchedWriters(const std::string& topic, std::function<std::uint32_t()> count);
  /// A per-robot topic's reader whose samples from a writer outside the named robot's partition are
  /// dropped (transport::Reader::foreign()): refresh() adds them to
  /// `<service>_rejected_samples_total{reason="foreign_robot"}`.
  void watchForeign(std::function<std::uint64_t()> total);
  /// A running total kept elsewhere (a node's own counters, read on the loop's thread): refresh()
  /// adds what it grew by to `counter`.
  void watchTotal(metrics::Counter& counter, std::function<std::uint64_t()> total);
  /// Beats the liveness and, at most once a second, updates the matched gauges (and pets the
  /// systemd watchdog). Call it on every turn of the service's loop, from the loop's thread. Returns
  /// true when it did the once-a-second part (so a loop can hang its own slow gauges on it).
  bool refresh();
  /// Tells the service manager the service is stopping (once; also done by refresh() after a stop
  /// request and by the destructor).
  void stopping();

 private:
  struct Watched {
    metrics::Gauge* gauge;
    std::function<std::uint32_t()> count;
  };
  std::string service_;
  metrics::Registry registry_;
  Health health_;
  OpsServer server_;
  std::vector<Watched> watched_;
  struct Total {
    metrics::Counter* counter;
    std::function<std::uint64_t()> total;
    std::uint64_t counted = 0;
  };
  std::vector<Total> totals_;
  std::chrono::steady_clock::time_point lastRefresh_{};
  bool readySent_ = false;
  bool stoppingSent_ = false;
  bool watchdog_ = false;
  bool notifyFailed_ = false;
  void notify(const char* state);
};

}  // namespace fleet::service
