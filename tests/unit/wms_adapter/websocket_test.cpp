// The server's WebSocket channel (for the live dashboard's routes): the handshake passes the same
// scope check as every route, messages go both ways, and open WebSockets hold no worker.

#include <gtest/gtest.h>

#include <boost/asio.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>
#include <mutex>
#include <thread>

#include "api_fixture.hpp"
#include "http_server.hpp"

using namespace fleet::wms;
using namespace fleet::wms::testing;
namespace net = boost::asio;
namespace beast = boost::beast;
namespace websocket = beast::websocket;
using tcp = net::ip::tcp;

namespace {

class WebSocket : public ::testing::Test {
 protected:
  void SetUp() override {
    ServerLimits limits;
    limits.threads = 1;
    limits.maxInFlight = 1;
    server_ = std::make_unique<HttpServer>(limits);
    server_->setGate([](Request& req, Response& res, Scope) {
      if (req.get_header_value("Authorization") != "Bearer ok") {
        res.status = 401;
        return false;
      }
      return true;
    });
    server_->route("GET", "/ws", Scope::Read, [this](const Request&, Response& res) {
      auto sent = std::make_shared<int>(0);
      res.acceptWebSocket({[sent]() -> std::optional<std::string> {
                             return *sent >= 3 ? std::string() : "message " + std::to_string((*sent)++);
                           },
                           [this](const std::string& text) {
                             std::lock_guard lock(m_);
                             received_.push_back(text);
                           }});
    });
    server_->route("GET", "/plain", Scope::Read,
                   [](const Request&, Response& res) { res.set_content("ok", "text/plain"); });
    ASSERT_TRUE(server_->bind("127.0.0.1", 0));
    thread_ = std::thread([this] { server_->serve(); });
  }
  void TearDown() override {
    server_->stop();
    thread_.join();
  }
  std::unique_ptr<websocket::stream<tcp::socket>> open(const std::string& authorization) {
    auto ws = std::make_unique<websocket::stream<tcp::socket>>(io_);
    ws->next_layer().connect({net::ip::address_v4::loopback(), static_cast<unsigned short>(server_->port())});
    ws->set_option(websocket::stream_base::decorator([authorization](websocket::request_type& r) {
      r.set(beast::http::field::authorization, authorization);
    }));
    ws->handshake("localhost", "/ws");
    return ws;
  }
  std::vector<std::string> received() {
    std::lock_guard lock(m_);
    return received_;
  }

  std::unique_ptr<HttpServer> server_;
  std::thread thread_;
  net::io_context io_;
  std::mutex m_;
  std::vector<std::string> received_;
};

}  // namespace

TEST_F(WebSocket, MessagesGoBothWays) {
  auto ws = open("Bearer ok");
  for (int i = 0; i < 3; ++i) {
    beast::flat_buffer b;
    ws->read(b);
    EXPECT_EQ(beast::buffers_to_string(b.data()), "message " + std::to_string(i));
  }
  ws->write(net::buffer(std::string("hello")));
  ws->close(websocket::close_code::normal);
  for (int i = 0; i < 200 && received().empty(); ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(25));
  }
  EXPECT_EQ(received(), std::vector<std::string>{"hello"});
}

TEST_F(WebSocket, TheHandshakePassesTheScopeCheck) {
  EXPECT_THROW(open("Bearer wrong"), boost::system::system_error);
  RawClient plain(server_->port());
  plain.send("GET /ws HTTP/1.1\r\nHost: x\r\nAuthorization: Bearer ok\r\n\r\n");
  const auto response = plain.receive("}");
  EXPECT_EQ(statusOf(response), 400) << response;
  EXPECT_NE(response.find("not_websocket"), std::string::npos);
}

TEST_F(WebSocket, OpenWebSocketsHoldNoWorker) {
  auto a = open("Bearer ok");
  auto b = open("Bearer ok");  // the server has one worker
  EXPECT_EQ(server_->stats().openStreams.load(), 2);
  RawClient plain(server_->port());
  plain.send("GET /plain HTTP/1.1\r\nHost: x\r\nAuthorization: Bearer ok\r\n\r\n");
  EXPECT_EQ(statusOf(plain.receive("ok")), 200);
}
