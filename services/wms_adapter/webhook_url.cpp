#include "webhook_url.hpp"

#include <algorithm>
#include <cctype>

namespace fleet::wms {

std::optional<WebhookUrl> parseWebhookUrl(const std::string& url, std::string* why) {
  auto fail = [&](const std::string& w) -> std::optional<WebhookUrl> {
    if (why != nullptr) {
      *why = w;
    }
    return std::nullopt;
  };
  if (url.size() > 2048) {
    return fail("longer than 2,048 characters");
  }
  if (std::any_of(url.begin(), url.end(),
                  [](char c) { return static_cast<unsigned char>(c) <= 0x20 || c == 0x7f; })) {
    return fail("contains a space or a control character");
  }
  WebhookUrl u;
  const auto sep = url.find("://");
  if (sep == std::string::npos) {
    return fail("not an absolute http:// or https:// URL");
  }
  u.scheme = url.substr(0, sep);
  std::transform(u.scheme.begin(), u.scheme.end(), u.scheme.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (u.scheme != "http" && u.scheme != "https") {
    return fail("scheme \"" + url.substr(0, sep) + "\": only http and https are delivered to");
  }
  if (url.find('#') != std::string::npos) {
    return fail("has a fragment (#)");
  }
  const auto rest = url.substr(sep + 3);
  const auto end = rest.find_first_of("/?");
  std::string authority = rest.substr(0, end);
  u.path = end == std::string::npos ? "/" : rest.substr(end);
  if (u.path[0] == '?') {
    u.path = "/" + u.path;
  }
  if (authority.find('@') != std::string::npos) {
    return fail("has user information (user@host): put no credentials in a webhook URL");
  }
  std::string port;
  if (!authority.empty() && authority[0] == '[') {
    const auto close = authority.find(']');
    if (close == std::string::npos) {
      return fail("an IPv6 host without its closing ]");
    }
    u.host = authority.substr(0, close + 1);
    if (close + 1 < authority.size()) {
      if (authority[close + 1] != ':') {
        return fail("text after the IPv6 host");
      }
      port = authority.substr(close + 2);
    }
  } else {
    const auto colon = authority.find(':');
    u.host = authority.substr(0, colon);
    if (colon != std::string::npos) {
      port = authority.substr(colon + 1);
    }
  }
  std::transform(u.host.begin(), u.host.end(), u.host.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (u.host.empty() || u.host == "[]") {
    return fail("no host");
  }
  if (port.empty()) {
    u.port = u.scheme == "https" ? 443 : 80;
  } else {
    if (port.size() > 5 ||
        !std::all_of(port.begin(), port.end(), [](char c) { return c >= '0' && c <= '9'; })) {
      return fail("port \"" + port + "\" is not a number in 1..65535");
    }
    u.port = std::stoi(port);
    if (u.port < 1 || u.port > 65535) {
      return fail("port " + port + " is not in 1..65535");
    }
  }
  u.origin = u.scheme + "://" + u.host + ":" + std::to_string(u.port);
  return u;
}

std::optional<std::string> refuseWebhookUrl(const std::string& url, const std::vector<std::string>& allow) {
  std::string why;
  const auto u = parseWebhookUrl(url, &why);
  if (!u) {
    return why;
  }
  if (allow.empty()) {
    return std::string("webhooks.allow is empty in the adapter's configuration: no URL may receive webhooks");
  }
  for (const auto& entry : allow) {
    const auto a = parseWebhookUrl(entry, nullptr);
    if (!a || a->origin != u->origin) {
      continue;
    }
    const auto& p = a->path;
    if (p == "/" || u->path == p ||
        (u->path.rfind(p, 0) == 0 &&
         (p.back() == '/' || u->path[p.size()] == '/' || u->path[p.size()] == '?'))) {
      return std::nullopt;
    }
  }
  return "not admitted by webhooks.allow (" + std::to_string(allow.size()) +
         " entries; scheme, host and port must match an entry exactly and the path start with its path)";
}

}  // namespace fleet::wms
