#include "http_server.hpp"

#include "fleet/core/config.hpp"
#include "request_parse.hpp"

#include <openssl/ssl.h>

#include <boost/asio.hpp>
#include <boost/asio/ssl.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/ssl.hpp>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <deque>
#include <mutex>
#include <nlohmann/json.hpp>
#include <regex>
#include <stdexcept>
#include <thread>
#include <unordered_map>

namespace fleet::wms {
namespace {

namespace beast = boost::beast;
namespace bhttp = beast::http;
namespace net = boost::asio;
namespace ssl = net::ssl;
using tcp = net::ip::tcp;
using SteadyClock = std::chrono::steady_clock;
using std::chrono::milliseconds;

bool sameName(std::string_view a, std::string_view b) {
  return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(), [](char x, char y) {
           return std::tolower(static_cast<unsigned char>(x)) == std::tolower(static_cast<unsigned char>(y));
         });
}

Response errorResponse(int status, const std::string& code, const std::string& message) {
  Response r;
  r.status = status;
  r.set_content(nlohmann::json{{"error", code}, {"message", message}}.dump(), "application/json");
  return r;
}

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

}  // namespace

std::string Request::get_header_value(const std::string& name) const {
  for (const auto& [k, v] : headers) {
    if (sameName(k, name)) {
      return v;
    }
  }
  return "";
}

bool Request::has_header(const std::string& name) const {
  return std::any_of(headers.begin(), headers.end(), [&](const auto& h) { return sameName(h.first, name); });
}

std::string Request::get_param_value(const std::string& name) const {
  auto it = params.find(name);
  return it == params.end() ? "" : it->second;
}

void Response::set_header(const std::string& name, const std::string& value) {
  for (auto& [k, v] : headers) {
    if (sameName(k, name)) {
      v = value;
      return;
    }
  }
  headers.emplace_back(name, value);
}

std::string Response::get_header_value(const std::string& name) const {
  for (const auto& [k, v] : headers) {
    if (sameName(k, name)) {
      return v;
    }
  }
  return "";
}

struct HttpServer::Impl {
  explicit Impl(ServerLimits l) : limits(l) {}

  ServerLimits limits;
  std::vector<Route> routes;
  std::vector<BodyLimit> bodyLimits;
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

namespace {

void runHandler(const Route& route, const Request& req, Response& res) {
  try {
    route.handler(req, res);
  } catch (const std::exception& e) {
    res = errorResponse(500, "internal", e.what());
  } catch (...) {
    res = errorResponse(500, "internal", "internal error");
  }
}

/// One connection: reads requests one after the other (no pipelining), hands each to the server,
/// writes the answer; or streams events. Everything runs on the I/O thread.
template <class Stream>
class Session : public std::enable_shared_from_this<Session<Stream>> {
 public:
  static constexpr bool kTls = !std::is_same_v<Stream, beast::tcp_stream>;

  Session(HttpServer::Impl& server, Stream stream, bool refuse, std::string remote)
      : server_(server),
        stream_(std::move(stream)),
        refuse_(refuse),
        remote_(std::move(remote)),
        timer_(server.io) {
    ++server_.sessions;
    ++(refuse_ ? server_.stats.refusedConnections : server_.stats.openConnections);
  }
  ~Session() {
    --server_.sessions;
    if (!refuse_) {
      --server_.stats.openConnections;
    }
    if (streaming_) {
      --server_.stats.openStreams;
    }
  }
  Session(const Session&) = delete;
  Session& operator=(const Session&) = delete;

  void start() {
    if constexpr (kTls) {
      tcp().expires_after(milliseconds(server_.limits.requestTimeoutMs));
      stream_.async_handshake(ssl::stream_base::server,
                              [self = this->shared_from_this()](beast::error_code ec) {
                                if (ec) {
                                  ++self->server_.stats.tlsFailures;
                                  return;
                                }
                                self->readRequest();
                              });
    } else {
      readRequest();
    }
  }

 private:
  beast::tcp_stream& tcp() { return beast::get_lowest_layer(stream_); }

  void readRequest() {
    parser_.emplace();
    parser_->body_limit(server_.limits.maxBodyBytes);
    parser_->header_limit(static_cast<std::uint32_t>(server_.limits.maxHeaderBytes));
    // The whole request, from now on, within the timeout: a client sending a byte at a time
    // (slowloris) is cut off, however often it sends.
    tcp().expires_after(milliseconds(refuse_ ? std::min(2000, server_.limits.requestTimeoutMs)
                                             : server_.limits.requestTimeoutMs));
    bodyLimit_ = {server_.limits.maxBodyBytes, "http.max_body_bytes"};
    // The head first: the route's own body limit applies to its body.
    bhttp::async_read_header(
        stream_, buffer_, *parser_,
        [self = this->shared_from_this()](beast::error_code ec, std::size_t) { self->onHeader(ec); });
  }

  void onHeader(beast::error_code ec) {
    if (ec) {
      onRead(ec);
      return;
    }
    Request target;
    const auto t = parser_->get().target();
    parseTarget(std::string_view(t.data(), t.size()), target);
    bodyLimit_ = server_.bodyLimitFor(std::string(parser_->get().method_string()), target.path);
    // A declared length was checked against the server's limit with the head: check the route's.
    if (const auto declared = parser_->content_length(); declared && *declared > bodyLimit_.first) {
      onRead(bhttp::error::body_limit);
      return;
    }
    parser_->body_limit(bodyLimit_.first);
    bhttp::async_read(
        stream_, buffer_, *parser_,
        [self = this->shared_from_this()](beast::error_code e, std::size_t) { self->onRead(e); });
  }

  /// The request as far as it was read (the head may be all there is).
  std::shared_ptr<Request> requestSoFar() {
    auto req = std::make_shared<Request>();
    req->remote_addr = remote_;
    if (parser_->is_header_done()) {
      const auto& msg = parser_->get();
      req->method = std::string(msg.method_string());
      req->target = std::string(msg.target());
      parseTarget(req->target, *req);
      for (const auto& f : msg) {
        req->headers.emplace_back(std::string(f.name_string()), std::string(f.value()));
      }
      version_ = msg.version();
      keepAlive_ = msg.keep_alive();
    }
    return req;
  }

  void onRead(beast::error_code ec) {
    started_ = SteadyClock::now();
    if (ec == bhttp::error::end_of_stream || ec == net::error::eof) {
      closeGracefully();
      return;
    }
    if (ec == beast::error::timeout) {
      ++server_.stats.timedOut;  // tcp_stream has closed the socket
      return;
    }
    auto req = requestSoFar();
    if (ec == bhttp::error::body_limit || ec == bhttp::error::header_limit) {
      ++server_.stats.tooLarge;
      const bool body = ec == bhttp::error::body_limit;
      finish(req,
             errorResponse(body ? 413 : 431, "too_large",
                           body ? "the body is larger than the limit of " + std::to_string(bodyLimit_.first) +
                                      " bytes for " + req->method + " " + req->path + " (" +
                                      bodyLimit_.second + ")"
                                : "the request head is larger than " +
                                      std::to_string(server_.limits.maxHeaderBytes) + " bytes"),
             true);
      return;
    }
    if (ec) {
      if (parser_->got_some() && ec != net::error::connection_reset) {
        finish(req, errorResponse(400, "bad_request", "malformed HTTP request: " + ec.message()), true);
      } else {
        tcp().close();
      }
      return;
    }
    req->body = std::move(parser_->get().body());
    if (refuse_) {
      auto res = errorResponse(503, "busy", "too many connections; retry");
      res.set_header("Retry-After", "1");
      finish(req, std::move(res), true);
      return;
    }
    server_.dispatch(req, [self = this->shared_from_this(), req](Response res) {
      self->finish(req, std::move(res), !self->keepAlive_);
    });
  }

  void finish(const std::shared_ptr<Request>& req, Response res, bool close) {
    if (res.events && server_.stats.openStreams.load() >= server_.limits.maxStreams) {
      ++server_.stats.refusedStreams;
      res = errorResponse(503, "busy", "too many open event streams; retry");
      res.set_header("Retry-After", "5");
    }
    if (server_.observer) {
      server_.observer(*req, res, std::chrono::duration<double>(SteadyClock::now() - started_).count());
    }
    if (res.events) {
      startStream(std::move(res));
    } else {
      write(std::move(res), close);
    }
  }

  template <class Message>
  void setHeaders(Message& msg, const Response& res) {
    msg.set(bhttp::field::content_type, res.contentType);
    for (const auto& [k, v] : res.headers) {
      msg.set(k, v);
    }
  }

  void write(Response res, bool close) {
    auto msg = std::make_shared<bhttp::response<bhttp::string_body>>(static_cast<bhttp::status>(res.status),
                                                                     version_);
    setHeaders(*msg, res);
    msg->body() = std::move(res.body);
    msg->keep_alive(!close);
    msg->prepare_payload();
    tcp().expires_after(milliseconds(server_.limits.writeTimeoutMs));
    bhttp::async_write(stream_, *msg,
                       [self = this->shared_from_this(), msg, close](beast::error_code ec, std::size_t) {
                         if (ec) {
                           return;
                         }
                         if (close) {
                           self->closeGracefully();
                         } else {
                           self->readRequest();
                         }
                       });
  }

  void startStream(Response res) {
    streaming_ = true;
    ++server_.stats.openStreams;
    source_ = std::move(res.events);
    auto head = std::make_shared<bhttp::response<bhttp::empty_body>>(bhttp::status::ok, version_);
    setHeaders(*head, res);
    head->chunked(true);
    auto sr = std::make_shared<bhttp::response_serializer<bhttp::empty_body>>(*head);
    tcp().expires_after(milliseconds(server_.limits.writeTimeoutMs));
    bhttp::async_write_header(stream_, *sr,
                              [self = this->shared_from_this(), head, sr](beast::error_code ec, std::size_t) {
                                if (ec) {
                                  return;
                                }
                                self->lastSent_ = SteadyClock::now();
                                self->waitForEvents();
                              });
  }

  void waitForEvents() {
    timer_.expires_after(milliseconds(server_.limits.streamPollMs));
    timer_.async_wait([self = this->shared_from_this()](beast::error_code ec) {
      if (!ec) {
        self->pollEvents();
      }
    });
  }

  void pollEvents() {
    std::optional<std::string> text;
    try {
      text = source_();
    } catch (...) {
      text.reset();
    }
    if (!text) {
      auto last = std::make_shared<decltype(bhttp::make_chunk_last())>(bhttp::make_chunk_last());
      net::async_write(stream_, *last,
                       [self = this->shared_from_this(), last](beast::error_code ec, std::size_t) {
                         if (!ec) {
                           self->closeGracefully();
                         }
                       });
      return;
    }
    if (text->empty()) {
      if (SteadyClock::now() - lastSent_ < milliseconds(server_.limits.streamKeepAliveMs)) {
        waitForEvents();
        return;
      }
      *text = ": keep-alive\n\n";  // also finds a client that went away
    }
    auto data = std::make_shared<std::string>(std::move(*text));
    tcp().expires_after(milliseconds(server_.limits.writeTimeoutMs));
    net::async_write(stream_, bhttp::make_chunk(net::const_buffer(data->data(), data->size())),
                     [self = this->shared_from_this(), data](beast::error_code ec, std::size_t) {
                       if (ec) {
                         return;
                       }
                       self->lastSent_ = SteadyClock::now();
                       self->waitForEvents();
                     });
  }

  /// Closes without a reset: stop sending, then read and drop what the client still sends (the
  /// rest of a refused body) for a short while, so that it reads our answer before the close.
  void closeGracefully() {
    beast::error_code ignored;
    if constexpr (kTls) {
      tcp().expires_after(milliseconds(1000));
      stream_.async_shutdown([self = this->shared_from_this()](beast::error_code) {
        beast::error_code ec;
        self->tcp().socket().close(ec);
      });
    } else {
      tcp().socket().shutdown(tcp::socket::shutdown_send, ignored);
      tcp().expires_after(milliseconds(1000));
      drain();
    }
  }

  void drain() {
    tcp().async_read_some(net::buffer(scratch_),
                          [self = this->shared_from_this()](beast::error_code ec, std::size_t n) {
                            self->drained_ += n;
                            if (ec || self->drained_ > 8 * self->server_.limits.maxBodyBytes) {
                              beast::error_code ignored;
                              self->tcp().socket().close(ignored);
                              return;
                            }
                            self->drain();
                          });
  }

  HttpServer::Impl& server_;
  Stream stream_;
  bool refuse_;
  std::string remote_;
  beast::flat_buffer buffer_;
  std::optional<bhttp::request_parser<bhttp::string_body>> parser_;
  std::pair<std::size_t, std::string> bodyLimit_;  // of the request being read, and its setting
  unsigned version_ = 11;
  bool keepAlive_ = true;
  SteadyClock::time_point started_ = SteadyClock::now();
  bool streaming_ = false;
  EventSource source_;
  net::steady_timer timer_;
  SteadyClock::time_point lastSent_;
  std::array<char, 16384> scratch_{};
  std::size_t drained_ = 0;
};

}  // namespace

void HttpServer::Impl::accept() {
  acceptor.async_accept([this](beast::error_code ec, tcp::socket socket) {
    if (ec == net::error::operation_aborted || !acceptor.is_open()) {
      return;
    }
    if (ec) {
      // Out of descriptors (EMFILE) and the like: try again shortly instead of spinning.
      acceptRetry.expires_after(milliseconds(50));
      acceptRetry.async_wait([this](beast::error_code e) {
        if (!e) {
          accept();
        }
      });
      return;
    }
    startSession(std::move(socket));
    accept();
  });
}

void HttpServer::Impl::startSession(tcp::socket socket) {
  // Past twice the limit even the 503 costs too much: close at once.
  if (sessions.load() >= 2 * limits.maxConnections) {
    ++stats.refusedConnections;
    beast::error_code ignored;
    socket.close(ignored);
    return;
  }
  const bool refuse = stats.openConnections.load() >= limits.maxConnections;
  beast::error_code ec;
  socket.set_option(tcp::no_delay(true), ec);
  auto endpoint = socket.remote_endpoint(ec);
  std::string remote = ec ? "?" : endpoint.address().to_string();
  if (tls) {
    std::make_shared<Session<beast::ssl_stream<beast::tcp_stream>>>(
        *this, beast::ssl_stream<beast::tcp_stream>(beast::tcp_stream(std::move(socket)), *tls), refuse,
        std::move(remote))
        ->start();
  } else {
    std::make_shared<Session<beast::tcp_stream>>(*this, beast::tcp_stream(std::move(socket)), refuse,
                                                 std::move(remote))
        ->start();
  }
}

std::optional<int> HttpServer::Impl::overRate(const std::string& client) {
  const auto now = SteadyClock::now();
  const double burst = std::max(1, limits.rateBurst);
  if (buckets.size() > 10'000) {
    // Forget the clients whose buckets have filled up again: they are as if new.
    std::erase_if(buckets, [&](const auto& kv) {
      return kv.second.tokens +
                 std::chrono::duration<double>(now - kv.second.last).count() * limits.ratePerClient >=
             burst;
    });
  }
  auto [it, fresh] = buckets.try_emplace(client, Bucket{burst, now});
  auto& b = it->second;
  b.tokens =
      std::min(burst, b.tokens + std::chrono::duration<double>(now - b.last).count() * limits.ratePerClient);
  b.last = now;
  if (b.tokens >= 1) {
    b.tokens -= 1;
    return std::nullopt;
  }
  return static_cast<int>(std::ceil((1 - b.tokens) / limits.ratePerClient));
}

void HttpServer::Impl::dispatch(const std::shared_ptr<Request>& req, std::function<void(Response)> done) {
  const Route* route = nullptr;
  std::smatch m;
  for (const auto& r : routes) {
    if (r.method == req->method && std::regex_match(req->path, m, r.pattern)) {
      route = &r;
      break;
    }
  }
  if (route == nullptr) {
    done(errorResponse(404, "not_found", "no route for " + req->method + " " + req->path));
    return;
  }
  for (const auto& g : m) {
    req->matches.push_back(g.str());
  }
  if (limits.ratePerClient > 0 && route->scope != Scope::Public) {
    if (const auto wait = overRate(req->remote_addr)) {
      ++stats.rateLimited;
      auto slow = errorResponse(429, "rate_limited", "more requests than http.rate_per_client allows; retry");
      slow.set_header("Retry-After", std::to_string(*wait));
      done(std::move(slow));
      return;
    }
  }
  Response res;
  if (gate && !gate(*req, res, route->scope)) {
    done(std::move(res));
    return;
  }
  if (route->run == Run::Inline) {
    runHandler(*route, *req, res);
    done(std::move(res));
    return;
  }
  // Waiting for a worker is bounded: past the limit the client hears 429 now instead of a
  // timeout later.
  if (inFlight.fetch_add(1) >= limits.maxInFlight) {
    --inFlight;
    ++stats.busy;
    auto busy = errorResponse(429, "busy", "too many requests in flight; retry");
    busy.set_header("Retry-After", "1");
    done(std::move(busy));
    return;
  }
  std::lock_guard lock(jobsMutex);
  jobs.emplace_back([this, route, req, done = std::move(done)]() mutable {
    Response r;
    runHandler(*route, *req, r);
    --inFlight;
    net::post(io, [done = std::move(done), r = std::move(r)]() mutable { done(std::move(r)); });
  });
  cv.notify_one();
}

void HttpServer::Impl::worker() {
  for (;;) {
    std::function<void()> job;
    {
      std::unique_lock lock(jobsMutex);
      cv.wait(lock, [&] { return stopping || !jobs.empty(); });
      if (stopping) {
        return;
      }
      job = std::move(jobs.front());
      jobs.pop_front();
    }
    job();
  }
}

HttpServer::HttpServer(ServerLimits limits, TlsFiles tls) : impl_(std::make_unique<Impl>(limits)) {
  if (!tls.enabled()) {
    return;
  }
  auto& ctx = impl_->tls.emplace(ssl::context::tls_server);
  ctx.set_options(ssl::context::default_workarounds | ssl::context::no_sslv2 | ssl::context::no_sslv3 |
                  ssl::context::no_tlsv1 | ssl::context::no_tlsv1_1 | ssl::context::single_dh_use);
  SSL_CTX_set_min_proto_version(ctx.native_handle(), TLS1_2_VERSION);
  // A configuration error (exit 2), naming the key and the file.
  try {
    ctx.use_certificate_chain_file(tls.certificateFile);
  } catch (const std::exception& e) {
    throw ConfigError({"http.tls_certificate: cannot use \"" + tls.certificateFile + "\": " + e.what()});
  }
  try {
    ctx.use_private_key_file(tls.privateKeyFile, ssl::context::pem);
  } catch (const std::exception& e) {
    throw ConfigError({"http.tls_key: cannot use \"" + tls.privateKeyFile + "\": " + e.what()});
  }
  if (SSL_CTX_check_private_key(ctx.native_handle()) != 1) {
    throw ConfigError({"http.tls_key: \"" + tls.privateKeyFile + "\" is not the key of the certificate \"" +
                       tls.certificateFile + "\" (http.tls_certificate)"});
  }
}

HttpServer::~HttpServer() = default;

void HttpServer::route(const std::string& method, const std::string& pattern, Scope scope, Handler handler,
                       Run run) {
  impl_->routes.push_back({method, pattern, std::regex(pattern), scope, std::move(handler), run});
}

std::vector<HttpServer::RouteInfo> HttpServer::routeTable() const {
  std::vector<RouteInfo> out;
  for (const auto& r : impl_->routes) {
    out.push_back({r.method, r.source, r.scope});
  }
  return out;
}

void HttpServer::limitBody(const std::string& method, const std::string& pattern, std::size_t bytes,
                           std::string configKey) {
  impl_->bodyLimits.push_back({method, std::regex(pattern), bytes, std::move(configKey)});
}

void HttpServer::setGate(Gate gate) {
  impl_->gate = std::move(gate);
}
void HttpServer::setObserver(Observer observer) {
  impl_->observer = std::move(observer);
}

bool HttpServer::bind(const std::string& host, int port) {
  auto& a = impl_->acceptor;
  beast::error_code ec;
  const auto address = net::ip::make_address(host, ec);
  if (ec) {
    impl_->lastError = "\"" + host + "\" is not an IP address";
    return false;
  }
  const tcp::endpoint endpoint(address, static_cast<unsigned short>(port));
  a.open(endpoint.protocol(), ec);
  // SO_REUSEADDR only (no SO_REUSEPORT): a second adapter on a taken port fails instead of sharing it.
  if (!ec) {
    a.set_option(net::socket_base::reuse_address(true), ec);
  }
  if (!ec) {
    a.bind(endpoint, ec);
  }
  if (!ec) {
    a.listen(impl_->limits.backlog, ec);
  }
  if (ec) {
    impl_->lastError = ec.message();
    a.close(ec);
    return false;
  }
  impl_->port = a.local_endpoint().port();
  return true;
}

int HttpServer::port() const {
  return impl_->port;
}
const std::string& HttpServer::lastError() const {
  return impl_->lastError;
}
const ServerStats& HttpServer::stats() const {
  return impl_->stats;
}

void HttpServer::serve() {
  std::vector<std::thread> workers;
  for (int i = 0; i < impl_->limits.threads; ++i) {
    workers.emplace_back([this] { impl_->worker(); });
  }
  impl_->accept();
  impl_->io.run();
  {
    std::lock_guard lock(impl_->jobsMutex);
    impl_->stopping = true;
  }
  impl_->cv.notify_all();
  for (auto& w : workers) {
    w.join();
  }
}

void HttpServer::stop() {
  net::post(impl_->io, [this] {
    beast::error_code ignored;
    impl_->acceptor.close(ignored);
  });
  impl_->io.stop();
}

}  // namespace fleet::wms
