#include "access_control.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <nlohmann/json.hpp>

namespace fleet::wms {
namespace {

bool credentialName(std::string name) {
  for (auto& c : name) {
    c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  }
  static const std::array<const char*, 7> kNames = {"access_token", "token",         "api_key", "apikey",
                                                    "bearer",       "authorization", "auth"};
  return std::find(kNames.begin(), kNames.end(), name) != kNames.end();
}

}  // namespace

AccessDecision AccessControl::check(const Request& req, Scope needed) const {
  AccessDecision d;
  d.principal = "-";
  for (const auto& [name, value] : req.params) {
    // Also a known token under any name: it has been exposed either way.
    if (credentialName(name) || (tokens_.enabled() && !value.empty() && tokens_.find(value))) {
      d.status = 400;
      d.code = "token_in_url";
      d.message = "credentials are never accepted in the URL (query parameter \"" + name +
                  "\"); send the header Authorization: Bearer <token>, and replace a token sent this way";
      return d;
    }
  }
  if (!tokens_.enabled()) {
    d.principal = "anonymous";
    return d;
  }
  const std::string header = req.get_header_value("Authorization");
  constexpr std::string_view kBearer = "Bearer ";
  std::optional<Principal> who;
  if (header.size() > kBearer.size() && header.compare(0, kBearer.size(), kBearer) == 0) {
    who = tokens_.find(std::string_view(header).substr(kBearer.size()));
  }
  std::optional<BrowserSessions::Session> session;
  if (header.empty() && sessions_ != nullptr) {
    const auto cookie = cookieValue(req.get_header_value("Cookie"), kSessionCookie);
    if (!cookie.empty()) {
      session = sessions_->check(cookie, std::chrono::duration_cast<std::chrono::seconds>(
                                             std::chrono::system_clock::now().time_since_epoch())
                                             .count());
      if (session) {
        who = session->who;
      }
    }
  }
  if (who) {
    d.principal = who->name;
  }
  if (needed == Scope::Public) {
    return d;
  }
  // Reading needs the cookie only; SameSite=Strict keeps other sites' pages from sending it, and
  // the CSRF header (which only our page can read from /v1/session) guards every change.
  const bool changes = req.method != "GET" && req.method != "HEAD" && req.method != "OPTIONS";
  if (!who) {
    d.status = 401;
    d.code = "unauthorized";
    d.message =
        sessions_ != nullptr ? "missing or wrong bearer token or session" : "missing or wrong bearer token";
  } else if (session && changes && !sameSecret(req.get_header_value(kCsrfHeader), session->csrf)) {
    d.status = 403;
    d.code = "csrf";
    d.message = std::string("missing or wrong ") + kCsrfHeader + " header";
  } else if (who->scopes.count(needed) == 0) {
    d.status = 403;
    d.code = "forbidden";
    d.message = "the token \"" + who->name + "\" lacks the \"" + toString(needed) + "\" scope";
  }
  return d;
}

bool AccessControl::admit(Request& req, Response& res, Scope needed) const {
  const auto d = check(req, needed);
  req.principal = d.principal;
  if (d.allowed()) {
    return true;
  }
  res.status = d.status;
  res.set_content(nlohmann::json{{"error", d.code}, {"message", d.message}}.dump(), "application/json");
  if (d.status == 401) {
    res.set_header("WWW-Authenticate", "Bearer");
  }
  return false;
}

}  // namespace fleet::wms
