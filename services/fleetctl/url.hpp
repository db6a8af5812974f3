#pragma once

// The WMS adapter's address as fleetctl takes it (--url): http:// or https://, a host, an optional
// port, nothing after. Strict, so a typo is an error rather than another port
// ("http://localhost:80x80" used to become port 80).

#include <string>

#include "fleet/core/expected.hpp"

namespace fleet::ctl {

struct Url {
  std::string scheme;  // "http" or "https"
  std::string host;    // a name, an IPv4 address, or an IPv6 address without brackets
  int port = 0;        // 80 / 443 when not given
  /// scheme://host:port, IPv6 in brackets: what httplib::Client takes.
  [[nodiscard]] std::string text() const;
};

/// Parses `text`; a scheme is required (no guessing between http and https).
Expected<Url> parseUrl(const std::string& text);

}  // namespace fleet::ctl
