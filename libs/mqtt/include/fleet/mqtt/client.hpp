#pragma once

// RAII over one libmosquitto client with its own network thread, which connects, and connects
// again after a lost connection or a broker restart (or when the broker was not up yet), once a
// second; the client subscribes again on every connect, so a caller never has to notice a restart
// except through connected() and the counters.

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "fleet/core/expected.hpp"

struct mosquitto;
struct mosquitto_message;

namespace fleet::mqtt {

/// The message the broker publishes for this client when it vanishes without a clean disconnect.
struct LastWill {
  std::string topic;
  std::string payload;
  int qos = 1;
  bool retain = false;
};

struct ClientOptions {
  std::string host = "127.0.0.1";
  int port = 1883;
  std::string client_id;
  std::string username;
  std::string password;
  std::optional<LastWill> will;
  int keepalive_s = 5;
  /// TLS: the CA that signed the broker's certificate (empty: plain TCP), and optionally this
  /// client's own certificate and key when the broker asks for one.
  std::string tls_ca_file;
  std::string tls_cert_file;
  std::string tls_key_file;
};

/// (topic, payload) of every message on a subscribed topic, called on the network thread.
using MessageHandler = std::function<void(const std::string& topic, const std::string& payload)>;

class Client {
 public:
  /// Starts the network thread and the first connection attempt; a broker that is not up yet is
  /// retried, so only bad options (not a missing broker) make this fail.
  static Expected<std::unique_ptr<Client>> start(ClientOptions options, MessageHandler on_message);
  ~Client();
  Client(const Client&) = delete;
  Client& operator=(const Client&) = delete;

  /// Subscribes now (when connected) and after every reconnect.
  void subscribe(const std::string& pattern, int qos);
  /// Queues a message; false when libmosquitto refuses it (e.g. not connected).
  bool publish(const std::string& topic, const std::string& payload, int qos, bool retain);
  [[nodiscard]] bool connected() const { return connected_.load(); }
  /// How many times a connection was established (1 after the first, +1 per reconnect).
  [[nodiscard]] std::uint64_t connects() const { return connects_.load(); }
  /// Connections the broker refused (bad credentials, ...).
  [[nodiscard]] std::uint64_t refusals() const { return refusals_.load(); }

 private:
  Client(ClientOptions options, MessageHandler on_message);
  static void onConnect(mosquitto* m, void* self, int rc);
  static void onDisconnect(mosquitto* m, void* self, int rc);
  static void onPublish(mosquitto* m, void* self, int mid);
  static void onMessage(mosquitto* m, void* self, const mosquitto_message* msg);

  ClientOptions options_;
  MessageHandler on_message_;
  mosquitto* handle_ = nullptr;
  std::mutex mutex_;
  std::vector<std::pair<std::string, int>> subscriptions_;
  std::atomic<bool> connected_{false};
  std::atomic<std::uint64_t> connects_{0};
  std::atomic<std::uint64_t> refusals_{0};
  std::atomic<bool> stopping_{false};
  /// Messages handed to publish() not yet sent (QoS 0) or acknowledged by the broker (QoS 1, 2).
  std::atomic<std::int64_t> unsent_{0};
  std::thread thread_;
};

}  // namespace fleet::mqtt
