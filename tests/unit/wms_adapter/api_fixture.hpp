#pragma once

// What the WMS adapter's API tests share: a manager in memory behind the TaskGateway interface, a
// small station map, and a fixture that serves the API on a free loopback port.

#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <httplib.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "http_api.hpp"
#include "openapi_contract.hpp"
#include "sqlite_db.hpp"

namespace fleet::wms::testing {

using nlohmann::json;

/// A manager in memory: stores tasks by id, answers duplicates and conflicts like the real one.
class FakeGateway : public TaskGateway {
 public:
  /// What makes two requests the same task (the manager compares canonical bodies).
  static std::string fields(const msg::Task& r) {
    return json{static_cast<int>(r.kind),
                r.pickup,
                r.dropoff,
                r.station,
                r.robot,
                r.load_ns,
                r.unload_ns,
                r.priority,
                r.deadline_ns,
                r.steps.size()}
        .dump();
  }

  std::vector<std::optional<msg::TaskAck>> submit(const std::vector<msg::Task>& requests,
                                                  std::chrono::milliseconds) override {
    std::vector<std::optional<msg::TaskAck>> out;
    if (delay.count() > 0) {
      std::this_thread::sleep_for(delay);
    }
    std::lock_guard lock(m_);  // the API calls from several workers at once
    for (const auto& r : requests) {
      if (silent) {
        out.emplace_back();
        continue;
      }
      msg::TaskAck a{r.request_id, r.task_id, msg::AckResult::Stored, msg::TaskState::Queued, "", 0};
      if (r.control != msg::TaskControl::None && onControl) {
        controls.push_back(r.control);
        controlRequests.push_back(r);
        out.emplace_back(onControl(r));
        continue;
      }
      if (r.cancel || r.control != msg::TaskControl::None) {
        auto it = bodies.find(r.task_id);
        a.result = it == bodies.end() ? msg::AckResult::NotFound : msg::AckResult::Stored;
        a.state = r.cancel ? msg::TaskState::Cancelled : msg::TaskState::EnRoute;
        controls.push_back(r.control);
      } else if (auto it = bodies.find(r.task_id); it != bodies.end()) {
        a.result = it->second == fields(r) ? msg::AckResult::Duplicate : msg::AckResult::Conflict;
      } else {
        bodies[r.task_id] = fields(r);
        stored.push_back(r);
      }
      out.emplace_back(a);
    }
    return out;
  }
  [[nodiscard]] bool managerOnline() const override { return online; }
  std::optional<std::string> sendClosure(const msg::TrafficClosure& c) override {
    std::lock_guard lock(m_);
    if (!closureProblem.empty()) {
      return closureProblem;
    }
    closuresSent.push_back(c);
    return std::nullopt;
  }
  [[nodiscard]] bool trafficManagerOnline() const override { return online; }
  std::vector<msg::TrafficClosure> closuresSent;
  std::string closureProblem;  // sendClosure fails with this when not empty
  std::map<std::string, std::string> bodies;
  std::vector<msg::Task> stored;  ///< the requests stored, in order
  std::vector<msg::TaskControl> controls;
  /// When set, answers every control request (pause, change, ...); they are kept in controlRequests.
  std::function<msg::TaskAck(const msg::Task&)> onControl;
  std::vector<msg::Task> controlRequests;
  bool online = true;
  bool silent = false;
  std::chrono::milliseconds delay{0};  // a slow manager

 private:
  std::mutex m_;
};

/// Checks every response an HttpApi makes against docs/openapi.yaml (OpenApiContract) as it is
/// made; a test's fixture reports what did not conform when the test ends.
class SpecWatch {
 public:
  void watch(HttpApi& api) {
    api.watchResponses([this](const Request& req, const Response& res) {
      auto found = test::OpenApiContract::shipped().checkResponse(req.method, req.path, res.status,
                                                                  res.contentType, res.body);
      std::lock_guard lock(m_);  // the server calls from its I/O thread
      problems_.insert(problems_.end(), found.begin(), found.end());
    });
  }
  /// One test failure per response that did not conform to the document.
  void report() {
    std::lock_guard lock(m_);
    for (const auto& p : problems_) {
      ADD_FAILURE() << "response does not match docs/openapi.yaml: " << p;
    }
    problems_.clear();
  }

 private:
  std::mutex m_;
  std::vector<std::string> problems_;
};

/// An event log file as an older adapter wrote it: table task_events with the columns of the first
/// version plus `extraColumns` (", priority INTEGER, ..."), and one event of task "old" logged `nowNs`
/// (not pruned). In a fresh directory `name`_<pid> under the temporary directory; returns the path.
inline std::string writeOlderEventLog(const std::string& name, const std::string& extraColumns,
                                      std::int64_t nowNs) {
  const auto dir = std::filesystem::temp_directory_path() / (name + "_" + std::to_string(getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const std::string path = (dir / "events.db").string();
  SqliteDb db(path);
  const std::string table =
      "CREATE TABLE task_events(id INTEGER PRIMARY KEY AUTOINCREMENT, task_id TEXT NOT NULL, seq INTEGER "
      "NOT NULL, state TEXT NOT NULL, robot TEXT NOT NULL, reason TEXT NOT NULL, stamp_ns INTEGER NOT "
      "NULL, station TEXT NOT NULL, logged_ns INTEGER NOT NULL" +
      extraColumns + ");";
  db.exec(table.c_str());
  const std::string row =
      "INSERT INTO task_events(task_id, seq, state, robot, reason, stamp_ns, station, logged_ns) "
      "VALUES ('old', 1, 'queued', '', 'submitted', 1, '', " +
      std::to_string(nowNs) + ");";
  db.exec(row.c_str());
  return path;
}

inline std::int64_t wallNowNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

inline StationMap stations() {
  return *StationMap::fromJson(json::parse(R"({"stations": [
    {"name": "P-1", "x": 1, "y": 1, "kinds": ["pickup"]},
    {"name": "D-1", "x": 5, "y": 1, "kinds": ["dropoff"]}]})"));
}

class Api : public ::testing::Test {
 protected:
  void start(ApiSettings s = {}) {
    s.port = 0;
    s.ackTimeoutMs = 200;
    api_ = std::make_unique<HttpApi>(s, stations_, gateway_, view_, clock_);
    spec_.watch(*api_);
    ASSERT_TRUE(api_->bind());
    thread_ = std::thread([this] { api_->serve(); });
    client_ = std::make_unique<httplib::Client>("127.0.0.1", api_->port());
  }
  void TearDown() override {
    if (api_) {
      api_->stop();
      thread_.join();
    }
    spec_.report();
  }
  httplib::Result post(const std::string& body, const httplib::Headers& h = {}) {
    return client_->Post("/v1/tasks", h, body, "application/json");
  }
  StationMap stations_ = stations();
  FakeGateway gateway_;
  FleetView view_;
  WallClock clock_;
  std::unique_ptr<HttpApi> api_;
  std::thread thread_;
  std::unique_ptr<httplib::Client> client_;
  SpecWatch spec_;
};

/// A client socket that does exactly what a test says, however rude: partial heads, endless
/// chunked bodies, requests it never reads the answer of.
class RawClient {
 public:
  explicit RawClient(int port) {
    fd_ = ::socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_port = htons(static_cast<std::uint16_t>(port));
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    connected_ = ::connect(fd_, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0;
  }
  ~RawClient() { ::close(fd_); }
  RawClient(const RawClient&) = delete;
  RawClient& operator=(const RawClient&) = delete;
  [[nodiscard]] bool connected() const { return connected_; }
  [[nodiscard]] int fd() const { return fd_; }
  /// False once the server has closed (or reset) the connection.
  bool send(const std::string& data) {
    return ::send(fd_, data.data(), data.size(), MSG_NOSIGNAL) == static_cast<ssize_t>(data.size());
  }
  /// What arrives until the peer closes, `until` appears, or `limit` passes (a bound so that a
  /// broken server fails the test instead of hanging it).
  std::string receive(const std::string& until = "",
                      std::chrono::milliseconds limit = std::chrono::seconds(20)) {
    std::string out;
    const auto end = std::chrono::steady_clock::now() + limit;
    while (std::chrono::steady_clock::now() < end) {
      pollfd p{fd_, POLLIN, 0};
      if (::poll(&p, 1, 50) <= 0) {
        continue;
      }
      char buf[4096];
      const auto n = ::recv(fd_, buf, sizeof buf, 0);
      if (n <= 0) {
        closedByPeer_ = true;
        break;
      }
      out.append(buf, static_cast<std::size_t>(n));
      if (!until.empty() && out.find(until) != std::string::npos) {
        break;
      }
    }
    return out;
  }
  [[nodiscard]] bool closedByPeer() const { return closedByPeer_; }

 private:
  int fd_ = -1;
  bool connected_ = false;
  bool closedByPeer_ = false;
};

/// The status code of a raw HTTP response ("HTTP/1.1 413 ..." -> 413), 0 if there is none.
inline int statusOf(const std::string& response) {
  if (response.rfind("HTTP/1.", 0) != 0 || response.size() < 12) {
    return 0;
  }
  return std::atoi(response.substr(9, 3).c_str());
}

inline std::string rawPost(const std::string& path, const std::string& body, const std::string& extra = "") {
  return "POST " + path + " HTTP/1.1\r\nHost: localhost\r\nContent-Type: application/json\r\n" + extra +
         "Content-Length: " + std::to_string(body.size()) + "\r\n\r\n" + body;
}

}  // namespace fleet::wms::testing
