#pragma once

// The MQTT side of one simulated VDA 5050 vehicle: its own broker credentials, a last will that
// says CONNECTIONBROKEN, ONLINE after every (re)connect and OFFLINE on a clean stop, orders and
// instant actions queued for the simulator thread, state and factsheet out. QoS and retain flags
// as the specification (2.1, section 6.2) gives them.

#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "fleet/core/expected.hpp"
#include "fleet/mqtt/client.hpp"
#include "fleet/vda5050/factsheet.hpp"
#include "fleet/vda5050/instant_actions.hpp"
#include "fleet/vda5050/order.hpp"
#include "fleet/vda5050/state.hpp"

namespace fleet::sim {

struct Vda5050LinkOptions {
  std::string host = "127.0.0.1";
  int port = 1883;
  std::string interface_name = "uagv";
  std::string manufacturer;
  std::string serial;
  std::string username;
  std::string password;
  std::string tls_ca_file;  // empty: plain TCP
};

struct Vda5050Inbox {
  std::vector<vda5050::Order> orders;
  std::vector<vda5050::InstantActions> instant_actions;
  std::vector<std::string> refused;  // why each unreadable message was dropped
};

class Vda5050Link {
 public:
  static Expected<std::unique_ptr<Vda5050Link>> start(Vda5050LinkOptions options);
  ~Vda5050Link();
  Vda5050Link(const Vda5050Link&) = delete;
  Vda5050Link& operator=(const Vda5050Link&) = delete;

  /// Everything received since the last call; also announces ONLINE after a (re)connect.
  Vda5050Inbox take(std::int64_t stamp_ns);
  bool publish(const vda5050::State& state);
  bool publish(const vda5050::Factsheet& factsheet);
  [[nodiscard]] bool connected() const { return client_->connected(); }
  [[nodiscard]] std::string topic(const std::string& name) const;

 private:
  explicit Vda5050Link(Vda5050LinkOptions options) : options_(std::move(options)) {}
  void onMessage(const std::string& topic, const std::string& payload);
  std::string connectionJson(const std::string& state, std::int64_t stamp_ns);

  Vda5050LinkOptions options_;
  std::unique_ptr<mqtt::Client> client_;
  std::mutex mutex_;
  Vda5050Inbox inbox_;
  std::uint64_t announced_connects_ = 0;
  std::uint32_t connection_header_ = 0;
};

}  // namespace fleet::sim
