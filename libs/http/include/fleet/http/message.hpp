#pragma once

// What a handler of the HTTP server (server.hpp) reads and writes. Request and Response carry the
// few accessors of cpp-httplib's that the handlers use, spelled as there, so a handler written for
// httplib::Server moves over by changing the two type names.

#include <functional>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace fleet::http {

struct Request {
  std::string method;  // "GET", "POST", ...
  std::string target;  // as sent (path and query); never logged: a client may put secrets there
  std::string path;    // percent-decoded path without the query
  std::multimap<std::string, std::string> params;  // decoded query parameters
  std::vector<std::pair<std::string, std::string>> headers;
  std::string body;
  std::vector<std::string> matches;  // the route pattern's groups, [0] = the whole path
  std::string remote_addr;
  std::string principal;  // who made the request (the token's name), set by the gate

  [[nodiscard]] std::string get_header_value(const std::string& name) const;
  [[nodiscard]] bool has_header(const std::string& name) const;
  [[nodiscard]] bool has_param(const std::string& name) const { return params.count(name) > 0; }
  [[nodiscard]] std::string get_param_value(const std::string& name) const;
};

/// Called on the I/O thread every poll interval: the text to send now (may be empty), or nothing
/// to end the stream. Must not block.
using EventSource = std::function<std::optional<std::string>()>;

struct Response {
  int status = 200;
  std::string body;
  std::string contentType = "text/plain";
  std::vector<std::pair<std::string, std::string>> headers;
  EventSource events;  // set: the response is an open-ended stream of this content type
  std::string audit;   // what the request changed, for the audit log (JSON text), set by handlers

  void set_content(std::string content, std::string type) {
    body = std::move(content);
    contentType = std::move(type);
  }
  void set_header(const std::string& name, const std::string& value);
  [[nodiscard]] std::string get_header_value(const std::string& name) const;
  /// Streams what `source` yields (server-sent events: "text/event-stream").
  void setEventStream(std::string type, EventSource source) {
    contentType = std::move(type);
    events = std::move(source);
  }
};

}  // namespace fleet::http
