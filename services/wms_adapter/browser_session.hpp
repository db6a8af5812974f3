#pragma once

// Browser sessions made from one of the API's bearer tokens (docs/operator-guide.md#dashboard). A
// session is a cookie: the token's name, an expiry and a random nonce, signed with HMAC-SHA256 keyed
// by the token's digest. So a session acts as the token it was made from (its name in the audit
// log, its scopes, re-read with the token file) and ends when that token changes or is removed.
// The adapter also keeps every live session in a table of its own (bounded, expired ones dropped):
// a cookie counts only while its session is there, so logging out (revoke) ends it at once and an
// adapter restart ends them all. Each session has a CSRF token (also derived from the nonce) that
// actions sent with the cookie must carry in the X-CSRF-Token header.

#include <cstdint>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>

#include "token_store.hpp"

namespace fleet::wms {

inline constexpr const char* kSessionCookie = "fleet_session";
inline constexpr const char* kCsrfHeader = "X-CSRF-Token";

class BrowserSessions {
 public:
  struct Session {
    Principal who;     // the token's name and its scopes as the token file says now
    std::string csrf;  // what X-CSRF-Token must carry for a request that changes something
  };

  /// `secure`: the API is served over https, so the cookie gets the Secure flag.
  /// `maxSessions`: live sessions kept; a new one beyond it ends the one that expires first.
  explicit BrowserSessions(const TokenStore& tokens, bool secure = false, std::int64_t lifetimeS = 12 * 3600,
                           std::size_t maxSessions = 10'000);

  /// A new session's cookie value for the token named `name`, valid until nowS + lifetime;
  /// nothing when no token has that name. Thread-safe.
  [[nodiscard]] std::optional<std::string> issue(const std::string& name, std::int64_t nowS);
  /// The session of a valid, unexpired, not revoked cookie whose token still exists unchanged;
  /// nothing else. Thread-safe.
  [[nodiscard]] std::optional<Session> check(std::string_view cookieValue, std::int64_t nowS) const;
  /// Ends the session of a valid cookie (logout): the cookie is refused from now on. False when
  /// the cookie names no live session. Thread-safe.
  bool revoke(std::string_view cookieValue, std::int64_t nowS);
  /// Live sessions in the table (expired ones may still be counted until the next issue).
  [[nodiscard]] std::size_t liveSessions() const;
  /// The Set-Cookie header value for a session (HttpOnly, SameSite=Strict, Path=/, Secure on https).
  [[nodiscard]] std::string setCookie(const std::string& value) const;
  /// The Set-Cookie header value that removes the session cookie.
  [[nodiscard]] std::string clearCookie() const;
  [[nodiscard]] std::int64_t lifetimeS() const { return lifetimeS_; }
  /// Who the token named `name` is now (its scopes as the token file says), or nothing.
  [[nodiscard]] std::optional<Principal> principal(std::string_view name) const;
  /// False when no token is configured (authentication off: no sessions needed).
  [[nodiscard]] bool enabled() const { return tokens_.enabled(); }

 private:
  /// The cookie's nonce when its signature holds; nothing else.
  [[nodiscard]] std::optional<std::string> verifiedNonce(std::string_view cookie, std::int64_t nowS,
                                                         std::optional<Session>* session) const;

  const TokenStore& tokens_;
  bool secure_;
  std::int64_t lifetimeS_;
  std::size_t maxSessions_;
  mutable std::mutex m_;
  std::map<std::string, std::int64_t> live_;  // nonce -> expiry (s)
};

/// The value of cookie `name` in a Cookie header ("a=1; fleet_session=xyz"), or empty.
std::string cookieValue(std::string_view cookieHeader, std::string_view name);
/// Equal strings, compared in time independent of where they differ.
bool sameSecret(std::string_view a, std::string_view b);

}  // namespace fleet::wms
