#include "browser_session.hpp"

#include <openssl/evp.h>
#include <openssl/hmac.h>
#include <openssl/rand.h>

#include <algorithm>
#include <array>
#include <charconv>
#include <stdexcept>

namespace fleet::wms {
namespace {

std::string hex(const unsigned char* p, std::size_t n) {
  static constexpr char kDigits[] = "0123456789abcdef";
  std::string s;
  s.reserve(2 * n);
  for (std::size_t i = 0; i < n; ++i) {
    s += kDigits[p[i] >> 4];
    s += kDigits[p[i] & 15];
  }
  return s;
}

/// HMAC-SHA256 of `what` keyed by a token's digest, in hex.
std::string mac(const TokenStore::Digest& key, std::string_view what) {
  std::array<unsigned char, EVP_MAX_MD_SIZE> out{};
  unsigned int n = 0;
  if (HMAC(EVP_sha256(), key.data(), static_cast<int>(key.size()),
           reinterpret_cast<const unsigned char*>(what.data()), what.size(), out.data(), &n) == nullptr) {
    throw std::runtime_error("HMAC-SHA256 failed");
  }
  return hex(out.data(), n);
}

}  // namespace

BrowserSessions::BrowserSessions(const TokenStore& tokens, bool secure, std::int64_t lifetimeS,
                                 std::size_t maxSessions)
    : tokens_(tokens),
      secure_(secure),
      lifetimeS_(lifetimeS),
      maxSessions_(std::max<std::size_t>(1, maxSessions)) {}

// The cookie is "<expiry>.<nonce>.<mac>.<name>": the name last, as it may hold dots itself.
std::optional<std::string> BrowserSessions::issue(const std::string& name, std::int64_t nowS) {
  const auto entry = tokens_.named(name);
  if (!entry) {
    return std::nullopt;
  }
  std::array<unsigned char, 16> nonce{};
  if (RAND_bytes(nonce.data(), static_cast<int>(nonce.size())) != 1) {
    throw std::runtime_error("no random bytes for a session");
  }
  const std::string nonceHex = hex(nonce.data(), nonce.size());
  {
    std::lock_guard lock(m_);
    if (live_.size() >= maxSessions_) {
      std::erase_if(live_, [&](const auto& kv) { return kv.second < nowS; });
    }
    if (live_.size() >= maxSessions_) {
      live_.erase(std::min_element(live_.begin(), live_.end(),
                                   [](const auto& a, const auto& b) { return a.second < b.second; }));
    }
    live_[nonceHex] = nowS + lifetimeS_;
  }
  const std::string body = std::to_string(nowS + lifetimeS_) + "." + nonceHex;
  return body + "." + mac(entry->digest, "session." + body + "." + name) + "." + name;
}

std::optional<Principal> BrowserSessions::principal(std::string_view name) const {
  auto entry = tokens_.named(name);
  return entry ? std::optional<Principal>(std::move(entry->who)) : std::nullopt;
}

std::optional<std::string> BrowserSessions::verifiedNonce(std::string_view cookie, std::int64_t nowS,
                                                          std::optional<Session>* session) const {
  if (cookie.size() > 512) {
    return std::nullopt;
  }
  const auto dot1 = cookie.find('.');
  const auto dot2 = dot1 == std::string_view::npos ? dot1 : cookie.find('.', dot1 + 1);
  const auto dot3 = dot2 == std::string_view::npos ? dot2 : cookie.find('.', dot2 + 1);
  if (dot3 == std::string_view::npos) {
    return std::nullopt;
  }
  const std::string body(cookie.substr(0, dot2));
  const std::string name(cookie.substr(dot3 + 1));
  const auto entry = tokens_.named(name);
  if (!entry || !sameSecret(cookie.substr(dot2 + 1, dot3 - dot2 - 1),
                            mac(entry->digest, "session." + body + "." + name))) {
    return std::nullopt;
  }
  std::int64_t expires = 0;
  const auto [end, ec] = std::from_chars(cookie.data(), cookie.data() + dot1, expires);
  if (ec != std::errc{} || end != cookie.data() + dot1 || expires < nowS) {
    return std::nullopt;
  }
  if (session != nullptr) {
    *session = Session{entry->who, mac(entry->digest, "csrf." + body + "." + name)};
  }
  return std::string(cookie.substr(dot1 + 1, dot2 - dot1 - 1));
}

std::optional<BrowserSessions::Session> BrowserSessions::check(std::string_view cookie,
                                                               std::int64_t nowS) const {
  std::optional<Session> session;
  const auto nonce = verifiedNonce(cookie, nowS, &session);
  if (!nonce) {
    return std::nullopt;
  }
  std::lock_guard lock(m_);
  const auto it = live_.find(*nonce);
  if (it == live_.end() || it->second < nowS) {
    return std::nullopt;  // logged out, pushed out of the table, or made before a restart
  }
  return session;
}

bool BrowserSessions::revoke(std::string_view cookie, std::int64_t nowS) {
  const auto nonce = verifiedNonce(cookie, nowS, nullptr);
  if (!nonce) {
    return false;
  }
  std::lock_guard lock(m_);
  return live_.erase(*nonce) > 0;
}

std::size_t BrowserSessions::liveSessions() const {
  std::lock_guard lock(m_);
  return live_.size();
}

std::string BrowserSessions::setCookie(const std::string& value) const {
  return std::string(kSessionCookie) + "=" + value + "; Path=/; HttpOnly; SameSite=Strict" +
         (secure_ ? "; Secure" : "") + "; Max-Age=" + std::to_string(lifetimeS_);
}

std::string BrowserSessions::clearCookie() const {
  return std::string(kSessionCookie) + "=; Path=/; HttpOnly; SameSite=Strict" + (secure_ ? "; Secure" : "") +
         "; Max-Age=0";
}

std::string cookieValue(std::string_view header, std::string_view name) {
  while (!header.empty()) {
    const auto semi = header.find(';');
    std::string_view part = header.substr(0, semi);
    header = semi == std::string_view::npos ? std::string_view{} : header.substr(semi + 1);
    while (!part.empty() && part.front() == ' ') {
      part.remove_prefix(1);
    }
    const auto eq = part.find('=');
    if (eq != std::string_view::npos && part.substr(0, eq) == name) {
      return std::string(part.substr(eq + 1));
    }
  }
  return {};
}

bool sameSecret(std::string_view a, std::string_view b) {
  if (a.size() != b.size()) {
    return false;
  }
  unsigned char diff = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    diff |= static_cast<unsigned char>(a[i] ^ b[i]);
  }
  return diff == 0;
}

}  // namespace fleet::wms
