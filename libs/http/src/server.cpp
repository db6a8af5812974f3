// The server's dispatch (routes, rate limit, gate, the bounded worker queue), its TLS context and
// its public interface.

#include <openssl/ssl.h>

#include <cmath>
#include <stdexcept>
#include <thread>

#include "error_response.hpp"
#include "fleet/core/config.hpp"
#include "server_impl.hpp"

namespace fleet::http {
namespace {

using detail::errorResponse;
using std::chrono::milliseconds;

void runHandler(const detail::Route& route, const Request& req, Response& res) {
  try {
    route.handler(req, res);
  } catch (const std::exception& e) {
    res = errorResponse(500, "internal", e.what());
  } catch (...) {
    res = errorResponse(500, "internal", "internal error");
  }
}

}  // namespace

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
  const detail::Route* route = nullptr;
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

}  // namespace fleet::http
