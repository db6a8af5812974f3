#pragma once

// An HTTP(S) server on Boost.Beast, written for the WMS adapter's API; any service may serve with
// it (see the commit that brought it: Debian's cpp-httplib 0.11 holds one worker thread per
// connection for its whole life, has a listen backlog of 5 compiled in, reads a chunked body whole
// before any limit, and has no in-flight bound that answers instead of queueing).
//
// What one client cannot do to it:
// - hold a thread by being slow: sockets are read and written asynchronously on one I/O thread, and
//   a request (head and body) must arrive within `requestTimeoutMs` of the connection waiting for
//   it, else the connection is closed;
// - send an unbounded body: Beast's parser stops at `maxBodyBytes` (or the route's limitBody)
//   whether the body comes with a Content-Length (refused before it is read) or chunked (refused
//   at the chunk that crosses it): 413;
// - fill the worker threads: handlers run on `threads` workers; beyond `maxInFlight` requests
//   being handled, a request gets 429 with Retry-After at once instead of waiting;
// - hold a thread with an event stream: a stream is polled from the I/O thread (EventSource must
//   not block) and holds no worker; beyond `maxStreams` open streams, 503 with Retry-After;
// - make the kernel reset connections: the listen backlog is `backlog`, and beyond `maxConnections`
//   open connections a new one is read and answered 503 with Retry-After, then closed;
// - send faster than `ratePerClient` (when set) from one address: 429 with Retry-After (public
//   routes, the health probe, are exempt).

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "fleet/http/message.hpp"
#include "fleet/http/scope.hpp"

namespace fleet::http {

struct ServerLimits {
  std::size_t maxBodyBytes = 1 << 20;
  std::size_t maxHeaderBytes = 16 * 1024;
  int maxConnections = 512;      // open connections; more are answered 503
  int maxStreams = 64;           // open event streams; more are answered 503
  int maxInFlight = 16;          // requests being handled or waiting for a worker; more get 429
  int threads = 16;              // handler threads
  int backlog = 1024;            // listen(2) backlog (the kernel caps it at net.core.somaxconn)
  int requestTimeoutMs = 10000;  // a whole request (head and body) must arrive within this
  int writeTimeoutMs = 30000;    // a response (or a stream's next chunk) must be taken within this
  int streamPollMs = 100;        // how often an event stream's source is asked
  int streamKeepAliveMs = 1000;  // an idle stream sends a comment this often
  double ratePerClient = 0;      // requests per second per client address (token bucket); 0 = no limit
  int rateBurst = 20;            // requests a client may send at once before its rate applies
};

/// PEM files for https; both empty = plain http.
struct TlsFiles {
  std::string certificateFile;  // the server's certificate (chain), PEM
  std::string privateKeyFile;   // its key, PEM
  [[nodiscard]] bool enabled() const { return !certificateFile.empty(); }
};

/// Counts since start, for metrics.
struct ServerStats {
  std::atomic<std::int64_t> openConnections{0};
  std::atomic<std::int64_t> openStreams{0};
  std::atomic<std::int64_t> refusedConnections{0};  // 503 at maxConnections
  std::atomic<std::int64_t> refusedStreams{0};      // 503 at maxStreams
  std::atomic<std::int64_t> busy{0};                // 429 at maxInFlight
  std::atomic<std::int64_t> rateLimited{0};         // 429 past ratePerClient
  std::atomic<std::int64_t> tooLarge{0};            // 413 / 431
  std::atomic<std::int64_t> timedOut{0};            // connections closed for a request too slow
  std::atomic<std::int64_t> tlsFailures{0};         // failed TLS handshakes
};

class HttpServer {
 public:
  using Handler = std::function<void(const Request&, Response&)>;
  /// Runs before a route's handler, on the I/O thread (must be quick): false = refused, with the
  /// reply written into the response. It may set Request::principal.
  using Gate = std::function<bool(Request&, Response&, Scope)>;
  /// Runs after every response is made, on the I/O thread (also the ones the server makes itself:
  /// 413, 429, 503, ...; those carry the API's error body {"error": code, "message": text}).
  using Observer = std::function<void(const Request&, const Response&, double seconds)>;
  /// Where a handler runs: on a worker (may block), or on the I/O thread (never blocks; probes).
  enum class Run { Worker, Inline };

  explicit HttpServer(ServerLimits limits, TlsFiles tls = {});
  ~HttpServer();
  HttpServer(const HttpServer&) = delete;
  HttpServer& operator=(const HttpServer&) = delete;

  /// `pattern` is an ECMAScript regex matched against the whole decoded path. Call before serve().
  void route(const std::string& method, const std::string& pattern, Scope scope, Handler handler,
             Run run = Run::Worker);
  /// Bodies of requests to `method` on paths matching `pattern` are limited to `bytes` (at most
  /// maxBodyBytes): a larger one is refused 413 (as soon as its length or a chunk says so), the
  /// message naming `configKey`, the setting that raises it. Call before serve().
  void limitBody(const std::string& method, const std::string& pattern, std::size_t bytes,
                 std::string configKey);
  void setGate(Gate gate);
  void setObserver(Observer observer);

  /// One registered route as route() was given it.
  struct RouteInfo {
    std::string method;
    std::string pattern;
    Scope scope;
  };
  /// Every route in registration order (docs/openapi.yaml must list each; ctest
  /// ApiContract.EveryRouteIsInTheSpecAndEverySpecPathIsARoute compares them).
  [[nodiscard]] std::vector<RouteInfo> routeTable() const;

  /// Binds and listens; false (and why in lastError()) when the address cannot be bound.
  bool bind(const std::string& host, int port);
  [[nodiscard]] int port() const;
  [[nodiscard]] const std::string& lastError() const;
  /// Serves until stop() (blocking).
  void serve();
  void stop();
  [[nodiscard]] const ServerStats& stats() const;

  struct Impl;  // Beast stays out of this header (and out of every file that includes it)

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace fleet::http
