#include "fleet/service/service_ops.hpp"

#include <spdlog/spdlog.h>

#include "fleet/service/command_line.hpp"
#include "fleet/service/runtime.hpp"
#include "fleet/service/systemd_notify.hpp"

namespace fleet::service {

ServiceOps::ServiceOps(std::string service) : service_(std::move(service)), server_(registry_, health_) {
  registry_
      .gauge("fleet_build_info", "Always 1; the labels name the service and the project version",
             {{"service", service_}, {"version", version()}})
      .set(1.0);
  // The family shows (HELP/TYPE) before the first rejection, so dashboards find it.
  rejected("none").inc(0);
}

ServiceOps::~ServiceOps() {
  stopping();
}

void ServiceOps::notify(const char* state) {
  if (const auto err = notifyServiceManager(state); !err.empty() && !notifyFailed_) {
    notifyFailed_ = true;  // once: a broken socket would otherwise log every second
    spdlog::warn("{}: {}", service_, err);
  }
}

void ServiceOps::stopping() {
  if (!stoppingSent_) {
    stoppingSent_ = true;
    notify("STOPPING=1");
  }
}

bool ServiceOps::start(const OpsSettings& s) {
  if (auto err = server_.start(s)) {
    spdlog::critical("{}: {}", service_, *err);
    return false;
  }
  if (s.port >= 0) {
    spdlog::info("{}: /metrics, /livez, /readyz on http://{}:{}", service_, s.host, server_.port());
  }
  return true;
}

metrics::Counter& ServiceOps::rejected(const std::string& key) {
  // A warning key may name the sender after a colon ("progress:r7"): the reason is the part before
  // it, so the label's values stay a small fixed set.
  const std::string reason = key.substr(0, key.find(':'));
  return registry_.counter(service_ + "_rejected_samples_total",
                           "Input samples dropped as invalid, by reason (the warning's key)",
                           {{"reason", reason}});
}

void ServiceOps::watchMatchedReaders(const std::string& topic, std::function<std::uint32_t()> count) {
  watched_.push_back(
      {&registry_.gauge("fleet_dds_matched_readers",
                        "Readers matched by this service's DDS writer of the topic", {{"topic", topic}}),
       std::move(count)});
}

void ServiceOps::watchMatchedWriters(const std::string& topic, std::function<std::uint32_t()> count) {
  watched_.push_back(
      {&registry_.gauge("fleet_dds_matched_writers",
                        "Writers matched by this service's DDS reader of the topic", {{"topic", topic}}),
       std::move(count)});
}

void ServiceOps::watchForeign(std::function<std::uint64_t()> total) {
  watchTotal(rejected("foreign_robot"), std::move(total));  // listed at 0 from the start
}

void ServiceOps::watchTotal(metrics::Counter& counter, std::function<std::uint64_t()> total) {
  totals_.push_back({&counter, std::move(total), 0});
}

bool ServiceOps::refresh() {
  health_.beat();
  if (!readySent_) {
    // The loop's first turn: everything it needs is set up, so the service serves.
    readySent_ = true;
    watchdog_ = watchdogPeriod().has_value();
    notify("READY=1");
  }
  if (stopRequested()) {
    stopping();
  }
  const auto now = std::chrono::steady_clock::now();
  if (now - lastRefresh_ < std::chrono::seconds(1)) {
    return false;
  }
  lastRefresh_ = now;
  if (watchdog_ && !stoppingSent_) {
    notify("WATCHDOG=1");  // from the loop's own thread: a stalled loop stops it, and systemd restarts
  }
  for (auto& w : watched_) {
    w.gauge->set(static_cast<double>(w.count()));
  }
  for (auto& t : totals_) {
    const std::uint64_t total = t.total();
    if (total > t.counted) {
      t.counter->inc(total - t.counted);
      t.counted = total;
    }
  }
  return true;
}

}  // namespace fleet::service
