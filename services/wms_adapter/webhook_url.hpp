#pragma once

// Where a webhook may deliver: an http(s) URL that an entry of `webhooks.allow` admits. An entry is
// a URL prefix — scheme, host and port compared exactly (default ports 80 / 443), path by whole
// segments — so "https://wms.example/hooks" admits "https://wms.example/hooks/fleet" but neither
// "https://wms.example/hooksX" nor "https://wms.example.evil/...".

#include <optional>
#include <string>
#include <vector>

namespace fleet::wms {

struct WebhookUrl {
  std::string scheme;  // "http" or "https"
  std::string host;    // lower case; an IPv6 address in brackets
  int port = 0;
  std::string path;    // "/" when none; with the query
  std::string origin;  // scheme://host:port, what an HTTP client connects to
};

/// The URL's parts, or why it is not an http(s) URL a webhook can use (userinfo, a fragment,
/// spaces or control characters, no host, a bad port, longer than 2,048 characters).
std::optional<WebhookUrl> parseWebhookUrl(const std::string& url, std::string* why);

/// Nothing when an entry of `allow` admits `url`, else why not (naming the allow-list).
std::optional<std::string> refuseWebhookUrl(const std::string& url, const std::vector<std::string>& allow);

}  // namespace fleet::wms
