#pragma once

// The mosquitto configuration for a fleet: a loopback (or given) listener, no anonymous clients,
// and an ACL that confines every vehicle to its own topic subtree while the master control (the
// bridge) may use the whole interface. Text only; writing files and hashing passwords
// (mosquitto_passwd) is the caller's business.

#include <cstddef>
#include <string>
#include <vector>

namespace fleet::mqtt {

struct BrokerUser {
  std::string name;
  std::string password;
  /// Topic filters this user may read and write, e.g. "uagv/v2/acme/AGV-1/#".
  std::vector<std::string> topics;
};

struct BrokerConfig {
  std::string bind_address = "127.0.0.1";
  int port = 0;
  std::string password_file;
  std::string acl_file;
  std::string log_file;  // empty: stderr
  /// TLS on the listener (all three set) or plain TCP (all empty).
  std::string tls_ca_file;
  std::string tls_cert_file;
  std::string tls_key_file;
  /// mosquitto started as root drops to the user "mosquitto" unless told otherwise; set this to
  /// "root" when the files it reads belong to root and are private.
  std::string run_as_user;
  /// Bytes of the largest message the broker takes (larger ones are dropped there): the bridge's
  /// own limit (vda5050_bridge max_message_bytes) is the same by default.
  std::size_t message_size_limit = 256 * 1024;
  std::vector<BrokerUser> users;
};

/// mosquitto.conf text (listener, password and ACL file, message size limit, no persistence).
std::string mosquittoConf(const BrokerConfig& config);
/// ACL file text: one "user" block per user with its topic filters.
std::string aclText(const BrokerConfig& config);

}  // namespace fleet::mqtt
