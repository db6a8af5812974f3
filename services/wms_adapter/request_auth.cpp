#include "request_auth.hpp"

#include <nlohmann/json.hpp>

namespace fleet::wms {

bool admitRequest(const std::string& token, const BrowserSessions& sessions, const httplib::Request& req,
                  httplib::Response& res, std::int64_t nowS) {
  // The page's files carry no data; health tells nothing secret and a probe carries no token.
  if (token.empty() || !req.path.starts_with("/v1/") || req.path == "/v1/health") {
    return true;
  }
  if (sameSecret(req.get_header_value("Authorization"), "Bearer " + token)) {
    return true;
  }
  const auto csrf = sessions.csrfOf(cookieValue(req.get_header_value("Cookie"), kSessionCookie), nowS);
  if (csrf) {
    // Reading needs the cookie only; SameSite=Strict keeps other sites' pages from sending it, and
    // the CSRF header (which only our page can read from /v1/session) guards every change.
    if (req.method == "GET" || req.method == "HEAD" || sameSecret(req.get_header_value(kCsrfHeader), *csrf)) {
      return true;
    }
    res.status = 403;
    res.set_content(nlohmann::json{{"error", "csrf"},
                                   {"message", std::string("missing or wrong ") + kCsrfHeader + " header"}}
                        .dump(),
                    "application/json");
    return false;
  }
  res.status = 401;
  res.set_header("WWW-Authenticate", "Bearer");
  res.set_content(
      nlohmann::json{{"error", "unauthorized"}, {"message", "missing or wrong bearer token or session"}}
          .dump(),
      "application/json");
  return false;
}

}  // namespace fleet::wms
