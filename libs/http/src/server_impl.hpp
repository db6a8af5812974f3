#pragma once

// The server's state, shared by its connections (connection.cpp) and its dispatch (server.cpp).
// Private to the library: Beast stays out of the public headers.

#include <boost/asio.hpp>
#include <boost/asio/ssl.hpp>
#include <boost/beast/core.hpp>
#include <chrono>
#include <condition_variable>
#include <deque>
#include <mutex>
#include <optional>
#include <regex>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "fleet/http/server.hpp"

namespace fleet::http {

namespace beast = boost::beast;
namespace net = boost::asio;
namespace ssl = net::ssl;
using tcp = net::ip::tcp;
using SteadyClock = std::chrono::steady_clock;

namespace detail {

struct BodyLimit {
  std::string method;
  std::regex pattern;
  std::size_t bytes;
  std::string configKey;
};

struct Route {
  std::string method;
  std::string source;  // the pattern as given
  std::regex pattern;
  Scope scope;
  HttpServer::Handler handler;
  HttpServer::Run run;
};

}  // namespace detail

struct HttpServer::Impl {
  explicit Impl(ServerLimits l) : limits(l) {}

  ServerLimits limits;
  std::vector<detail::Route> routes;
  std::vector<detail::BodyLimit> bodyLimits;
  Gate gate;
  Observer observer;
  ServerStats stats;
  std::atomic<int> inFlight{0};
  std::atomic<int> sessions{0};  // every connection held, the refused ones too
  int port = 0;
  std::string lastError;

  std::mutex jobsMutex;
  std::condition_variable cv;
  std::deque<std::function<void()>> jobs;
  bool stopping = false;

  /// Token buckets by client address (I/O thread only).
  struct Bucket {
    double tokens = 0;
    SteadyClock::time_point last;
  };
  std::unordered_map<std::string, Bucket> buckets;

  std::optional<ssl::context> tls;
  // Declared last: destroying it destroys the sessions its queue still holds, which use the above.
  net::io_context io{1};
  tcp::acceptor acceptor{io};
  net::steady_timer acceptRetry{io};

  /// The body limit of a request (the route's, else the server's) and the setting that says so.
  [[nodiscard]] std::pair<std::size_t, std::string> bodyLimitFor(const std::string& method,
                                                                 const std::string& path) const {
    for (const auto& l : bodyLimits) {
      if (l.method == method && std::regex_match(path, l.pattern)) {
        return {std::min(l.bytes, limits.maxBodyBytes), l.configKey};
      }
    }
    return {limits.maxBodyBytes, "http.max_body_bytes"};
  }
  void accept();
  void startSession(tcp::socket socket);
  void dispatch(const std::shared_ptr<Request>& req, std::function<void(Response)> done);
  /// Takes a token of `client`'s bucket; else the seconds until one is there.
  std::optional<int> overRate(const std::string& client);
  void worker();
};

}  // namespace fleet::http
