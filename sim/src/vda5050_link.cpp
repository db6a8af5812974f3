#include "fleet/sim/vda5050_link.hpp"

#include <chrono>

#include "fleet/vda5050/connection.hpp"
#include "fleet/vda5050/header.hpp"

namespace fleet::sim {

namespace {
std::int64_t wallNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}
}  // namespace

std::string Vda5050Link::topic(const std::string& name) const {
  return vda5050::topicName(options_.interface_name, options_.manufacturer, options_.serial, name);
}

std::string Vda5050Link::connectionJson(const std::string& state, std::int64_t stamp_ns) {
  vda5050::Connection c;
  c.header = {connection_header_++, vda5050::isoTimestamp(stamp_ns), vda5050::kVersion, options_.manufacturer,
              options_.serial};
  c.connectionState = state;
  return vda5050::toJson(c).dump();
}

Expected<std::unique_ptr<Vda5050Link>> Vda5050Link::start(Vda5050LinkOptions options) {
  if (options.manufacturer.empty() || options.serial.empty()) {
    return unexpected("vda5050.bad_options", "vda5050 vehicle: manufacturer and serial number must be set");
  }
  std::unique_ptr<Vda5050Link> link(new Vda5050Link(std::move(options)));
  mqtt::ClientOptions co;
  co.host = link->options_.host;
  co.port = link->options_.port;
  co.client_id = link->options_.manufacturer + "-" + link->options_.serial;
  co.username = link->options_.username;
  co.password = link->options_.password;
  co.tls_ca_file = link->options_.tls_ca_file;
  // The broker publishes this when the vehicle vanishes; its timestamp is the connect time, as
  // the specification allows.
  co.will =
      mqtt::LastWill{link->topic("connection"), link->connectionJson("CONNECTIONBROKEN", wallNs()), 1, true};
  auto* raw = link.get();
  auto client =
      mqtt::Client::start(co, [raw](const std::string& t, const std::string& p) { raw->onMessage(t, p); });
  if (!client) {
    return unexpected(client.error());
  }
  link->client_ = std::move(*client);
  link->client_->subscribe(link->topic("order"), 0);
  link->client_->subscribe(link->topic("instantActions"), 0);
  return link;
}

Vda5050Link::~Vda5050Link() {
  if (client_ && client_->connected()) {
    client_->publish(topic("connection"), connectionJson("OFFLINE", wallNs()), 1, true);
  }
}

void Vda5050Link::onMessage(const std::string& t, const std::string& payload) {
  std::lock_guard lock(mutex_);
  if (t == topic("order")) {
    if (auto o = vda5050::parseOrder(payload)) {
      inbox_.orders.push_back(std::move(*o));
    } else {
      inbox_.refused.push_back(o.error().message);
    }
  } else if (t == topic("instantActions")) {
    if (auto ia = vda5050::parseInstantActions(payload)) {
      inbox_.instant_actions.push_back(std::move(*ia));
    } else {
      inbox_.refused.push_back(ia.error().message);
    }
  }
}

Vda5050Inbox Vda5050Link::take(std::int64_t stamp_ns) {
  const auto connects = client_->connects();
  if (connects != announced_connects_ && client_->connected()) {
    if (client_->publish(topic("connection"), connectionJson("ONLINE", stamp_ns), 1, true)) {
      announced_connects_ = connects;
    }
  }
  std::lock_guard lock(mutex_);
  return std::exchange(inbox_, {});
}

bool Vda5050Link::publish(const vda5050::State& state) {
  return client_->publish(topic("state"), vda5050::toJson(state).dump(), 0, false);
}

bool Vda5050Link::publish(const vda5050::Factsheet& factsheet) {
  return client_->publish(topic("factsheet"), vda5050::toJson(factsheet).dump(), 0, true);
}

}  // namespace fleet::sim
