#pragma once

// Browser sessions made from one of the API's bearer tokens (docs/operator-guide.md#dashboard). A
// session is a cookie the adapter can check without remembering it: the token's name, an expiry
// and a random nonce, signed with HMAC-SHA256 keyed by the token's digest. So a session acts as
// the token it was made from (its name in the audit log, its scopes, re-read with the token file),
// it survives an adapter restart, and it ends when that token changes or is removed. Each session
// has a CSRF token (also derived from the nonce) that actions sent with the cookie must carry in
// the X-CSRF-Token header.

#include <cstdint>
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
  explicit BrowserSessions(const TokenStore& tokens, bool secure = false, std::int64_t lifetimeS = 12 * 3600);

  /// A new session's cookie value for the token named `name`, valid until nowS + lifetime;
  /// nothing when no token has that name.
  [[nodiscard]] std::optional<std::string> issue(const std::string& name, std::int64_t nowS) const;
  /// The session of a valid, unexpired cookie whose token still exists unchanged; nothing else.
  [[nodiscard]] std::optional<Session> check(std::string_view cookieValue, std::int64_t nowS) const;
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
  const TokenStore& tokens_;
  bool secure_;
  std::int64_t lifetimeS_;
};

/// The value of cookie `name` in a Cookie header ("a=1; fleet_session=xyz"), or empty.
std::string cookieValue(std::string_view cookieHeader, std::string_view name);
/// Equal strings, compared in time independent of where they differ.
bool sameSecret(std::string_view a, std::string_view b);

}  // namespace fleet::wms
