#include "fleet/service/ops_server.hpp"

#include <httplib.h>

#include <sys/socket.h>

#include <cerrno>
#include <cstring>

namespace fleet::service {

void bindExclusively(httplib::Server& server) {
  server.set_socket_options([](socket_t sock) {
    int yes = 1;
    setsockopt(sock, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof(yes));
  });
}

OpsServer::OpsServer(const metrics::Registry& registry, const Health& health)
    : registry_(registry), health_(health), server_(std::make_unique<httplib::Server>()) {
  // A few threads, fixed: scrapes and probes at the same time; a flood of probes queues rather than
  // spawning threads (each answer is a few atomic loads). A kept-alive connection holds its thread
  // while idle, so idle ones are closed after a second.
  server_->new_task_queue = [] { return new httplib::ThreadPool(4); };
  server_->set_keep_alive_timeout(1);
  server_->set_tcp_nodelay(true);  // small answers: no Nagle delay behind the previous one
  bindExclusively(*server_);
  server_->Get("/metrics", [this](const httplib::Request&, httplib::Response& res) {
    res.set_content(registry_.exposition(), "text/plain; version=0.0.4; charset=utf-8");
  });
  auto probe = [](httplib::Response& res, const ProbeAnswer& a) {
    res.status = a.ok ? 200 : 503;
    res.set_header("Cache-Control", "no-store");
    res.set_content(a.text, "text/plain; charset=utf-8");
  };
  server_->Get("/livez", [this, probe](const httplib::Request&, httplib::Response& res) {
    probe(res, health_.liveness());
  });
  server_->Get("/readyz", [this, probe](const httplib::Request&, httplib::Response& res) {
    probe(res, health_.readiness());
  });
}

OpsServer::~OpsServer() {
  stop();
}

std::optional<std::string> OpsServer::start(const OpsSettings& s) {
  if (s.port < 0) {
    return std::nullopt;
  }
  if (s.port > 65535) {
    return "metrics port " + std::to_string(s.port) + " is out of range (0-65535)";
  }
  errno = 0;
  const int bound =
      s.port == 0 ? server_->bind_to_any_port(s.host) : (server_->bind_to_port(s.host, s.port) ? s.port : -1);
  if (bound < 0) {
    const int err = errno;
    return "cannot listen on " + s.host + ":" + std::to_string(s.port) + " for /metrics" +
           (err != 0 ? std::string(": ") + std::strerror(err) : std::string());
  }
  port_ = bound;
  thread_ = std::thread([this] { server_->listen_after_bind(); });
  return std::nullopt;
}

void OpsServer::stop() {
  if (thread_.joinable()) {
    server_->stop();
    thread_.join();
  }
}

}  // namespace fleet::service
