#include "fleet/mqtt/client.hpp"

#include <mosquitto.h>

#include <chrono>
#include <mutex>

namespace fleet::mqtt {

namespace {
void initLibraryOnce() {
  static std::once_flag once;
  std::call_once(once, [] { mosquitto_lib_init(); });
}
}  // namespace

Client::Client(ClientOptions options, MessageHandler on_message)
    : options_(std::move(options)), on_message_(std::move(on_message)) {}

Expected<std::unique_ptr<Client>> Client::start(ClientOptions options, MessageHandler on_message) {
  initLibraryOnce();
  if (options.client_id.empty()) {
    return unexpected("mqtt.bad_options", "mqtt: client_id is empty");
  }
  if (options.port <= 0 || options.port > 65535) {
    return unexpected("mqtt.bad_options", "mqtt: port " + std::to_string(options.port) + " is out of range");
  }
  std::unique_ptr<Client> c(new Client(std::move(options), std::move(on_message)));
  c->handle_ = mosquitto_new(c->options_.client_id.c_str(), true, c.get());
  if (c->handle_ == nullptr) {
    return unexpected("mqtt.no_client", "mqtt: mosquitto_new failed for " + c->options_.client_id);
  }
  mosquitto_int_option(c->handle_, MOSQ_OPT_PROTOCOL_VERSION, MQTT_PROTOCOL_V311);
  if (!c->options_.username.empty()) {
    mosquitto_username_pw_set(c->handle_, c->options_.username.c_str(), c->options_.password.c_str());
  }
  if (!c->options_.tls_ca_file.empty()) {
    const auto opt = [](const std::string& s) { return s.empty() ? nullptr : s.c_str(); };
    const int rc = mosquitto_tls_set(c->handle_, c->options_.tls_ca_file.c_str(), nullptr,
                                     opt(c->options_.tls_cert_file), opt(c->options_.tls_key_file), nullptr);
    if (rc != MOSQ_ERR_SUCCESS) {
      return unexpected("mqtt.tls",
                        "mqtt: TLS with CA '" + c->options_.tls_ca_file + "': " + mosquitto_strerror(rc));
    }
  }
  if (c->options_.will) {
    const auto& w = *c->options_.will;
    const int rc = mosquitto_will_set(c->handle_, w.topic.c_str(), static_cast<int>(w.payload.size()),
                                      w.payload.data(), w.qos, w.retain);
    if (rc != MOSQ_ERR_SUCCESS) {
      return unexpected("mqtt.bad_will", "mqtt: last will on '" + w.topic + "': " + mosquitto_strerror(rc));
    }
  }
  mosquitto_connect_callback_set(c->handle_, &Client::onConnect);
  mosquitto_disconnect_callback_set(c->handle_, &Client::onDisconnect);
  mosquitto_message_callback_set(c->handle_, &Client::onMessage);
  mosquitto_publish_callback_set(c->handle_, &Client::onPublish);
  mosquitto_threaded_set(c->handle_, true);
  // The first attempt here, so that bad options fail at once; a broker that is down (refused,
  // unreachable) is tried again by the network thread.
  const int rc = mosquitto_connect_async(c->handle_, c->options_.host.c_str(), c->options_.port,
                                         c->options_.keepalive_s);
  if (rc != MOSQ_ERR_SUCCESS && rc != MOSQ_ERR_ERRNO && rc != MOSQ_ERR_EAI) {
    return unexpected("mqtt.connect", "mqtt: connect to " + c->options_.host + ":" +
                                          std::to_string(c->options_.port) + ": " + mosquitto_strerror(rc));
  }
  auto* raw = c.get();
  const bool first_ok = rc == MOSQ_ERR_SUCCESS;
  c->thread_ = std::thread([raw, first_ok] {
    bool have_socket = first_ok;
    while (true) {
      if (!have_socket) {
        // Once a second, in short sleeps so that stopping is quick.
        for (int i = 0; i < 20 && !raw->stopping_.load(); ++i) {
          std::this_thread::sleep_for(std::chrono::milliseconds(50));
        }
        if (raw->stopping_.load()) {
          return;
        }
        have_socket = mosquitto_reconnect_async(raw->handle_) == MOSQ_ERR_SUCCESS;
        continue;
      }
      if (mosquitto_loop(raw->handle_, 100, 1) != MOSQ_ERR_SUCCESS) {
        have_socket = false;
        raw->connected_.store(false);
      }
    }
  });
  return c;
}

Client::~Client() {
  if (handle_ != nullptr) {
    // A clean disconnect: the broker drops the last will (it is for connections that break).
    if (connected_.load()) {
      // Queued messages (an OFFLINE before the disconnect) leave first: until the broker has
      // acknowledged them (QoS 1) or they are written (QoS 0), for 2 s at most. Waiting only for the
      // queue to empty (200 ms) lost the OFFLINE when the network thread was slow to run.
      for (int i = 0; i < 200 && (unsent_.load() > 0 || mosquitto_want_write(handle_)) && connected_.load();
           ++i) {
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
      }
    }
    // The network thread sends the disconnect and, its socket closed, sees stopping_ and ends.
    stopping_.store(true);
    mosquitto_disconnect(handle_);
    if (thread_.joinable()) {
      thread_.join();
    }
    mosquitto_destroy(handle_);
  }
}

void Client::subscribe(const std::string& pattern, int qos) {
  std::lock_guard lock(mutex_);
  subscriptions_.emplace_back(pattern, qos);
  if (connected_.load()) {
    mosquitto_subscribe(handle_, nullptr, pattern.c_str(), qos);
  }
}

bool Client::publish(const std::string& topic, const std::string& payload, int qos, bool retain) {
  unsent_.fetch_add(1);
  const bool ok = mosquitto_publish(handle_, nullptr, topic.c_str(), static_cast<int>(payload.size()),
                                    payload.data(), qos, retain) == MOSQ_ERR_SUCCESS;
  if (!ok) {
    unsent_.fetch_sub(1);
  }
  return ok;
}

void Client::onConnect(mosquitto* m, void* self, int rc) {
  auto* c = static_cast<Client*>(self);
  if (rc != 0) {
    c->refusals_.fetch_add(1);
    return;
  }
  std::lock_guard lock(c->mutex_);
  for (const auto& [pattern, qos] : c->subscriptions_) {
    mosquitto_subscribe(m, nullptr, pattern.c_str(), qos);
  }
  c->connected_.store(true);
  c->connects_.fetch_add(1);
}

void Client::onDisconnect(mosquitto* /*m*/, void* self, int /*rc*/) {
  static_cast<Client*>(self)->connected_.store(false);
}

void Client::onPublish(mosquitto* /*m*/, void* self, int /*mid*/) {
  static_cast<Client*>(self)->unsent_.fetch_sub(1);
}

void Client::onMessage(mosquitto* /*m*/, void* self, const mosquitto_message* msg) {
  auto* c = static_cast<Client*>(self);
  if (c->on_message_ && msg->topic != nullptr) {
    const std::string payload(static_cast<const char*>(msg->payload),
                              static_cast<std::size_t>(msg->payloadlen));
    c->on_message_(msg->topic, payload);
  }
}

}  // namespace fleet::mqtt
