#include "url.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>

namespace fleet::ctl {

std::string Url::text() const {
  const bool v6 = host.find(':') != std::string::npos;
  return scheme + "://" + (v6 ? "[" + host + "]" : host) + ":" + std::to_string(port);
}

Expected<Url> parseUrl(const std::string& text) {
  auto bad = [&](const std::string& why) {
    return unexpected("invalid", "--url \"" + text + "\": " + why + " (expected http[s]://HOST[:PORT])");
  };
  Url u;
  const auto sep = text.find("://");
  if (sep == std::string::npos) {
    return bad("no scheme");
  }
  u.scheme = text.substr(0, sep);
  if (u.scheme != "http" && u.scheme != "https") {
    return bad("the scheme must be http or https");
  }
  std::string rest = text.substr(sep + 3);
  if (!rest.empty() && rest.back() == '/') {
    rest.pop_back();  // "http://host:8080/" is the same address
  }
  if (rest.find_first_of("/?#@") != std::string::npos) {
    return bad("a path, query or user part is not allowed");
  }
  std::string portText;
  if (!rest.empty() && rest.front() == '[') {
    const auto close = rest.find(']');
    if (close == std::string::npos) {
      return bad("unterminated IPv6 address");
    }
    u.host = rest.substr(1, close - 1);
    const std::string after = rest.substr(close + 1);
    if (!after.empty() && after.front() != ':') {
      return bad("unexpected text after the IPv6 address");
    }
    portText = after.empty() ? "" : after.substr(1);
    if (after == ":") {
      return bad("empty port");
    }
  } else {
    const auto colon = rest.find(':');
    u.host = rest.substr(0, colon);
    if (colon != std::string::npos) {
      portText = rest.substr(colon + 1);
      if (portText.empty()) {
        return bad("empty port");
      }
    }
    const bool hostOk = std::all_of(u.host.begin(), u.host.end(), [](char c) {
      return std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '-' || c == '.' || c == '_';
    });
    if (!hostOk) {
      return bad("the host has characters a host name cannot have");
    }
  }
  if (u.host.empty()) {
    return bad("no host");
  }
  if (portText.empty()) {
    u.port = u.scheme == "https" ? 443 : 80;
  } else {
    const auto [p, ec] = std::from_chars(portText.data(), portText.data() + portText.size(), u.port);
    if (ec != std::errc() || p != portText.data() + portText.size() || u.port < 1 || u.port > 65535) {
      return bad("the port must be a number from 1 to 65535");
    }
  }
  return u;
}

}  // namespace fleet::ctl
