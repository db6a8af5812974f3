// One connection of the server: TLS handshake, reading a request within its limits, the answer or
// an event stream, a graceful close; and accepting connections (refusing past maxConnections).

#include <openssl/ssl.h>

#include <array>
#include <boost/beast/http.hpp>
#include <boost/beast/ssl.hpp>

#include "error_response.hpp"
#include "fleet/http/request_parse.hpp"
#include "server_impl.hpp"

namespace fleet::http {
namespace {

namespace bhttp = beast::http;
using detail::errorResponse;
using std::chrono::milliseconds;

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

}  // namespace fleet::http
