#pragma once

// Browser sessions made from the API's bearer token (docs/operator-guide.md#dashboard). A session
// is a cookie the adapter can check without remembering it: an expiry and a random nonce signed
// with HMAC-SHA256 keyed by the token. So sessions survive an adapter restart, and every one ends
// when the token changes. Each session has a CSRF token (also derived from the nonce) that
// actions sent with the cookie must carry in the X-CSRF-Token header.

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace fleet::wms {

inline constexpr const char* kSessionCookie = "fleet_session";
inline constexpr const char* kCsrfHeader = "X-CSRF-Token";

class BrowserSessions {
 public:
  /// `token`: the API's bearer token (empty: no authentication, no sessions needed).
  explicit BrowserSessions(std::string token, std::int64_t lifetimeS = 12 * 3600);

  /// A new session's cookie value, valid until nowS + lifetime.
  [[nodiscard]] std::string issue(std::int64_t nowS) const;
  /// The CSRF token of a valid, unexpired session cookie; nothing for anything else.
  [[nodiscard]] std::optional<std::string> csrfOf(std::string_view cookieValue, std::int64_t nowS) const;
  /// The Set-Cookie header value for a session (HttpOnly, SameSite=Strict, Path=/).
  [[nodiscard]] std::string setCookie(const std::string& value) const;
  /// The Set-Cookie header value that removes the session cookie.
  [[nodiscard]] static std::string clearCookie();
  [[nodiscard]] std::int64_t lifetimeS() const { return lifetimeS_; }

 private:
  [[nodiscard]] std::string mac(std::string_view what) const;

  std::string token_;
  std::int64_t lifetimeS_;
};

/// The value of cookie `name` in a Cookie header ("a=1; fleet_session=xyz"), or empty.
std::string cookieValue(std::string_view cookieHeader, std::string_view name);
/// Equal strings, compared in time independent of where they differ.
bool sameSecret(std::string_view a, std::string_view b);

}  // namespace fleet::wms
