#pragma once

// Who may do what on the API: the one check every route goes through (the server's gate runs it
// with the scope the route was registered with). A route that authorizes by itself calls check()
// with the scope it needs. A browser session cookie (browser_session.hpp)
// stands for the token it was made from; a request with it that changes something also needs the
// session's CSRF token.

#include <string>

#include "browser_session.hpp"
#include "http_names.hpp"
#include "token_store.hpp"

namespace fleet::wms {

struct AccessDecision {
  int status = 0;         // 0: allowed; else 400 (credentials in the URL), 401 or 403 (scope, CSRF)
  std::string principal;  // the token's name; "anonymous" when authentication is off; "-" if unknown
  std::string code;       // the error body's "error" (when refused)
  std::string message;    // and its "message"
  [[nodiscard]] bool allowed() const { return status == 0; }
};

class AccessControl {
 public:
  /// `tokens` disabled (no token configured): every request is allowed, as "anonymous".
  /// `sessions` (may be null: bearer tokens only) admits the dashboard's session cookies.
  explicit AccessControl(const TokenStore& tokens, const BrowserSessions* sessions = nullptr)
      : tokens_(tokens), sessions_(sessions) {}

  /// A credential in the query string is refused before anything else (URLs end up in logs,
  /// proxies and browser histories); then the bearer token (or, without an Authorization header,
  /// the session cookie) must exist and grant `needed`.
  [[nodiscard]] AccessDecision check(const Request& req, Scope needed) const;
  /// check() as the server's gate: on refusal writes the reply (and WWW-Authenticate on 401).
  bool admit(Request& req, Response& res, Scope needed) const;

 private:
  const TokenStore& tokens_;
  const BrowserSessions* sessions_;
};

}  // namespace fleet::wms
