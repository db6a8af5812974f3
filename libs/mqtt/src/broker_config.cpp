#include "fleet/mqtt/broker_config.hpp"

namespace fleet::mqtt {

std::string mosquittoConf(const BrokerConfig& config) {
  std::string s;
  s += "per_listener_settings false\n";
  s += "listener " + std::to_string(config.port) + " " + config.bind_address + "\n";
  if (!config.tls_cert_file.empty()) {
    s += "cafile " + config.tls_ca_file + "\n";
    s += "certfile " + config.tls_cert_file + "\n";
    s += "keyfile " + config.tls_key_file + "\n";
  }
  s += "allow_anonymous false\n";
  s += "password_file " + config.password_file + "\n";
  s += "acl_file " + config.acl_file + "\n";
  s += "persistence false\n";
  s += "message_size_limit " + std::to_string(config.message_size_limit) + "\n";
  s += config.log_file.empty() ? std::string("log_dest stderr\n") : "log_dest file " + config.log_file + "\n";
  if (!config.run_as_user.empty()) {
    s += "user " + config.run_as_user + "\n";
  }
  s += "log_type error\nlog_type warning\nlog_type notice\n";
  return s;
}

std::string aclText(const BrokerConfig& config) {
  std::string s;
  for (const auto& u : config.users) {
    s += "user " + u.name + "\n";
    for (const auto& t : u.topics) {
      s += "topic readwrite " + t + "\n";
    }
    s += "\n";
  }
  return s;
}

}  // namespace fleet::mqtt
