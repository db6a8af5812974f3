#pragma once

// A Mosquitto broker of the test's own: a free loopback port (never 1883), a generated config with
// one user per vehicle confined by the ACL to its topic subtree and a master user for the whole
// interface, files in a fresh temporary directory. Stopped (and the directory removed) when the
// object goes out of scope; stop() and start() again keep the port, for broker-restart tests.

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <memory>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "fleet/mqtt/broker_config.hpp"
#include "test_process.hpp"

namespace fleet::test {

struct BrokerVehicle {
  std::string manufacturer;
  std::string serial;
  std::string password;
  [[nodiscard]] std::string user() const { return manufacturer + "-" + serial; }
};

class MosquittoBroker {
 public:
  static constexpr const char* kMasterUser = "master";
  static constexpr const char* kMasterPassword = "master-secret";

  /// `tls`: the listener speaks TLS only, with a certificate for 127.0.0.1 signed by a CA made
  /// here (caFile()).
  explicit MosquittoBroker(std::vector<BrokerVehicle> vehicles, bool tls = false,
                           std::string interface_name = "uagv")
      : vehicles_(std::move(vehicles)), interface_(std::move(interface_name)), tls_(tls) {
    static int counter = 0;
    dir_ = std::filesystem::temp_directory_path() /
           ("fleet-mosquitto-" + std::to_string(::getpid()) + "-" + std::to_string(counter++));
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
    if (tls_) {
      makeCertificates();
    }
    for (int attempt = 0; attempt < 5; ++attempt) {
      port_ = freePort();
      writeConfig();
      if (startOnce()) {
        return;
      }
    }
    throw std::runtime_error("mosquitto did not start; see " + (dir_ / "mosquitto.log").string());
  }
  MosquittoBroker(const MosquittoBroker&) = delete;
  MosquittoBroker& operator=(const MosquittoBroker&) = delete;
  ~MosquittoBroker() {
    stop();
    std::error_code ec;
    std::filesystem::remove_all(dir_, ec);
  }

  [[nodiscard]] int port() const { return port_; }
  [[nodiscard]] const std::string& interfaceName() const { return interface_; }
  [[nodiscard]] std::filesystem::path logFile() const { return dir_ / "mosquitto.log"; }
  [[nodiscard]] std::string caFile() const { return tls_ ? (dir_ / "ca.crt").string() : std::string(); }

  void stop() {
    if (process_) {
      process_->kill(SIGTERM);
      if (process_->wait(std::chrono::seconds(10)) < 0) {
        process_->kill(SIGKILL);
      }
      process_.reset();
    }
  }
  void start() {
    if (!process_ && !startOnce()) {
      throw std::runtime_error("mosquitto did not restart on port " + std::to_string(port_));
    }
  }

 private:
  static bool accepts(int port) {
    const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    a.sin_port = htons(static_cast<std::uint16_t>(port));
    const bool ok = ::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0;
    ::close(fd);
    return ok;
  }

  void openssl(const std::vector<std::string>& args) {
    ChildProcess p("/usr/bin/openssl", args);
    if (p.wait(std::chrono::seconds(60)) != 0) {
      throw std::runtime_error("openssl " + args.front() + " failed");
    }
  }

  void makeCertificates() {
    const auto f = [&](const char* name) { return (dir_ / name).string(); };
    openssl({"req", "-x509", "-newkey", "rsa:2048", "-nodes", "-days", "1", "-subj", "/CN=fleet-test-ca",
             "-keyout", f("ca.key"), "-out", f("ca.crt")});
    openssl({"req", "-newkey", "rsa:2048", "-nodes", "-subj", "/CN=127.0.0.1", "-addext",
             "subjectAltName=IP:127.0.0.1", "-keyout", f("server.key"), "-out", f("server.csr")});
    openssl({"x509", "-req", "-in", f("server.csr"), "-CA", f("ca.crt"), "-CAkey", f("ca.key"),
             "-CAcreateserial", "-days", "1", "-copy_extensions", "copyall", "-out", f("server.crt")});
  }

  void writeConfig() {
    mqtt::BrokerConfig c;
    c.port = port_;
    c.password_file = (dir_ / "passwd").string();
    c.acl_file = (dir_ / "acl").string();
    c.log_file = (dir_ / "mosquitto.log").string();
    if (tls_) {
      c.tls_ca_file = (dir_ / "ca.crt").string();
      c.tls_cert_file = (dir_ / "server.crt").string();
      c.tls_key_file = (dir_ / "server.key").string();
    }
    if (::getuid() == 0) {
      c.run_as_user = "root";
    }
    c.users.push_back({kMasterUser, kMasterPassword, {interface_ + "/#"}});
    for (const auto& v : vehicles_) {
      c.users.push_back(
          {v.user(), v.password, {interface_ + "/v2/" + v.manufacturer + "/" + v.serial + "/#"}});
    }
    std::ofstream(dir_ / "mosquitto.conf") << mqtt::mosquittoConf(c);
    std::ofstream(dir_ / "acl") << mqtt::aclText(c);
    std::ofstream(dir_ / "passwd").close();
    for (const auto& u : c.users) {
      ChildProcess p("/usr/bin/mosquitto_passwd", {"-b", c.password_file, u.name, u.password});
      if (p.wait(std::chrono::seconds(20)) != 0) {
        throw std::runtime_error("mosquitto_passwd failed for " + u.name);
      }
    }
  }

  bool startOnce() {
    process_ = std::make_unique<ChildProcess>(
        "/usr/sbin/mosquitto", std::vector<std::string>{"-c", (dir_ / "mosquitto.conf").string()});
    const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(10);
    while (std::chrono::steady_clock::now() < end) {
      if (process_->wait(std::chrono::milliseconds(0)) >= 0) {
        process_.reset();  // exited: the port was taken after all, or a bad config
        return false;
      }
      if (accepts(port_)) {
        return true;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    process_.reset();
    return false;
  }

  std::vector<BrokerVehicle> vehicles_;
  std::string interface_;
  bool tls_ = false;
  std::filesystem::path dir_;
  int port_ = 0;
  std::unique_ptr<ChildProcess> process_;
};

}  // namespace fleet::test
