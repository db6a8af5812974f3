#pragma once

// A webhook receiver for tests (webhooks_test.cpp, event_log_shared_test.cpp).

#include <gtest/gtest.h>
#include <httplib.h>

#include <chrono>
#include <map>
#include <mutex>
#include <set>
#include <string>
#include <thread>
#include <vector>

namespace fleet::wms::testing {

/// A webhook receiver on a free loopback port: answers each POST as `mode` says (ok, fail: 500,
/// slow: answers after `slowMs`) and keeps what it was sent.
class Receiver {
 public:
  enum class Mode { Ok, Fail, Slow };
  Receiver() {
    server_.Post("/hooks/fleet", [this](const httplib::Request& req, httplib::Response& res) {
      Mode mode;
      {
        std::lock_guard lock(m_);
        mode = script_.empty() ? mode_ : script_.front();
        if (!script_.empty()) {
          script_.erase(script_.begin());
        }
        ++attempts_;
      }
      if (mode == Mode::Slow) {
        std::this_thread::sleep_for(std::chrono::milliseconds(slowMs));
      }
      if (mode == Mode::Fail) {
        res.status = 500;
        return;
      }
      std::lock_guard lock(m_);
      got_.push_back({req.body, req.get_header_value("X-Fleet-Event-Id"),
                      req.get_header_value("X-Fleet-Timestamp"), req.get_header_value("X-Fleet-Signature"),
                      req.get_header_value("X-Fleet-Webhook-Id"), mode == Mode::Slow});
      res.status = 204;
    });
    port_ = server_.bind_to_any_port("127.0.0.1");
    thread_ = std::thread([this] { server_.listen_after_bind(); });
  }
  ~Receiver() {
    server_.stop();
    thread_.join();
  }
  Receiver(const Receiver&) = delete;
  Receiver& operator=(const Receiver&) = delete;
  [[nodiscard]] std::string url() const {
    return "http://127.0.0.1:" + std::to_string(port_) + "/hooks/fleet";
  }
  void set(Mode m, std::vector<Mode> script = {}) {
    std::lock_guard lock(m_);
    mode_ = m;
    script_ = std::move(script);
  }
  struct Got {
    std::string body, eventId, timestamp, signature, webhook;
    bool late;  // answered after the adapter's timeout (the adapter sends it again)
  };
  std::vector<Got> got() {
    std::lock_guard lock(m_);
    return got_;
  }
  int attempts() {
    std::lock_guard lock(m_);
    return attempts_;
  }
  /// The distinct event ids received, waiting up to 10 s for `n` of them.
  std::set<std::int64_t> waitFor(std::size_t n) {
    const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(10);
    std::set<std::int64_t> ids;
    while (std::chrono::steady_clock::now() < end) {
      ids.clear();
      for (const auto& g : got()) {
        ids.insert(std::stoll(g.eventId));
      }
      if (ids.size() >= n) {
        break;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    return ids;
  }
  /// How many times each event id was received.
  std::map<std::int64_t, int> timesById() {
    std::map<std::int64_t, int> n;
    for (const auto& g : got()) {
      ++n[std::stoll(g.eventId)];
    }
    return n;
  }
  int slowMs = 600;

 private:
  httplib::Server server_;
  int port_ = 0;
  std::thread thread_;
  std::mutex m_;
  Mode mode_ = Mode::Ok;
  std::vector<Mode> script_;
  std::vector<Got> got_;
  int attempts_ = 0;
};

}  // namespace fleet::wms::testing
