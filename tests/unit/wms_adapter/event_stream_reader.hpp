#pragma once

// A reader of the WMS adapter's event streams (GET /v1/events, the dashboard's GET /v1/stream) for
// tests that change what a stream reports while they follow it (wms_api_test.cpp,
// status_push_test.cpp, dashboard_test.cpp).

#include <httplib.h>

#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <functional>
#include <future>
#include <mutex>
#include <string>
#include <thread>
#include <utility>

namespace fleet::wms::testing {

/// Follows an event stream on a thread of its own until `until` holds for what has arrived.
/// Without since= GET /v1/events starts with the next new event, so a test publishes only once
/// waitOpen() is true: the server fixes the stream's start before it sends the response head. The
/// dashboard's stream makes its snapshot later, when the server first polls it, so a test changes
/// the fleet only once waitFor("event: snapshot") is true. The server's keep-alive comments (one a
/// second) keep a client's read timeout from ever firing, so the reader also gives up after
/// `limit`: a lost event fails the test instead of hanging it.
class EventStreamReader {
 public:
  /// True when what has arrived so far is enough.
  using Until = std::function<bool(const std::string&)>;

  /// Follows GET /v1/events until `until` has arrived.
  EventStreamReader(int port, const std::string& until, std::chrono::seconds limit = std::chrono::seconds(20))
      : EventStreamReader(
            port, "/v1/events",
            [until](const std::string& received) { return received.find(until) != std::string::npos; },
            limit) {}
  EventStreamReader(int port, std::string path, Until until,
                    std::chrono::seconds limit = std::chrono::seconds(20))
      : until_(std::move(until)), limit_(limit), opened_(openedPromise_.get_future()) {
    thread_ = std::thread([this, port, path = std::move(path)] {
      httplib::Client c("127.0.0.1", port);
      c.set_read_timeout(5, 0);
      const auto end = std::chrono::steady_clock::now() + limit_;
      bool told = false;
      c.Get(
          path,
          [&](const httplib::Response& r) {
            told = true;
            openedPromise_.set_value(r.status == 200);
            return r.status == 200;
          },
          [&](const char* data, std::size_t n) {
            std::lock_guard lock(mutex_);
            received_.append(data, n);
            arrived_ = until_(received_);
            changed_.notify_all();
            return !arrived_ && std::chrono::steady_clock::now() < end;
          });
      if (!told) {
        openedPromise_.set_value(false);  // no answer: connection refused or timed out
      }
      std::lock_guard lock(mutex_);
      stopped_ = true;
      changed_.notify_all();
    });
  }
  ~EventStreamReader() { finish(); }
  EventStreamReader(const EventStreamReader&) = delete;
  EventStreamReader& operator=(const EventStreamReader&) = delete;
  /// True once the server has answered 200 with the stream's head (events from now on arrive).
  bool waitOpen() { return opened_.wait_for(limit_) == std::future_status::ready && opened_.get(); }
  /// Waits until `what` holds for what has arrived (true), or the reader has stopped without it.
  bool waitFor(const Until& what) {
    std::unique_lock lock(mutex_);
    changed_.wait(lock, [&] { return what(received_) || stopped_; });
    return what(received_);
  }
  bool waitFor(const std::string& text) {
    return waitFor([&text](const std::string& received) { return received.find(text) != std::string::npos; });
  }
  /// Waits for the reader to stop (`until` arrived, the stream ended, or `limit` passed); true when
  /// `until` arrived.
  bool finish() {
    if (thread_.joinable()) {
      thread_.join();
    }
    return arrived_;
  }
  /// What has arrived so far.
  [[nodiscard]] std::string received() const {
    std::lock_guard lock(mutex_);
    return received_;
  }

 private:
  Until until_;
  std::chrono::seconds limit_;
  std::promise<bool> openedPromise_;
  std::future<bool> opened_;
  mutable std::mutex mutex_;
  std::condition_variable changed_;
  std::string received_;
  bool arrived_ = false;
  bool stopped_ = false;
  std::thread thread_;
};

}  // namespace fleet::wms::testing
