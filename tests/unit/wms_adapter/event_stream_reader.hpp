#pragma once

// A reader of the WMS adapter's event stream (GET /v1/events) for tests that publish events while
// they follow it (wms_api_test.cpp, status_push_test.cpp).

#include <httplib.h>

#include <chrono>
#include <cstddef>
#include <future>
#include <string>
#include <thread>
#include <utility>

namespace fleet::wms::testing {

/// Follows GET /v1/events on a thread of its own until `until` has arrived. Without since= the
/// stream starts with the next new event, so a test publishes only once waitOpen() is true: the
/// server fixes the stream's start before it sends the response head. The server's keep-alive
/// comments (one a second) keep a client's read timeout from ever firing, so the reader also gives
/// up after `limit`: a lost event fails the test instead of hanging it.
class EventStreamReader {
 public:
  EventStreamReader(int port, std::string until, std::chrono::seconds limit = std::chrono::seconds(20))
      : until_(std::move(until)), limit_(limit), opened_(openedPromise_.get_future()) {
    thread_ = std::thread([this, port] {
      httplib::Client c("127.0.0.1", port);
      c.set_read_timeout(5, 0);
      const auto end = std::chrono::steady_clock::now() + limit_;
      bool told = false;
      c.Get(
          "/v1/events",
          [&](const httplib::Response& r) {
            told = true;
            openedPromise_.set_value(r.status == 200);
            return r.status == 200;
          },
          [&](const char* data, std::size_t n) {
            received_.append(data, n);
            arrived_ = received_.find(until_) != std::string::npos;
            return !arrived_ && std::chrono::steady_clock::now() < end;
          });
      if (!told) {
        openedPromise_.set_value(false);  // no answer: connection refused or timed out
      }
    });
  }
  ~EventStreamReader() { finish(); }
  EventStreamReader(const EventStreamReader&) = delete;
  EventStreamReader& operator=(const EventStreamReader&) = delete;
  /// True once the server has answered 200 with the stream's head (events from now on arrive).
  bool waitOpen() { return opened_.wait_for(limit_) == std::future_status::ready && opened_.get(); }
  /// Waits for the reader to stop (`until` arrived, the stream ended, or `limit` passed); true when
  /// `until` arrived.
  bool finish() {
    if (thread_.joinable()) {
      thread_.join();
    }
    return arrived_;
  }
  /// What arrived; read after finish().
  [[nodiscard]] const std::string& received() const { return received_; }

 private:
  std::string until_;
  std::chrono::seconds limit_;
  std::promise<bool> openedPromise_;
  std::future<bool> opened_;
  std::string received_;
  bool arrived_ = false;
  std::thread thread_;
};

}  // namespace fleet::wms::testing
