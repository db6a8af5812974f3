#include "vda5050_setup.hpp"

#include <sys/wait.h>
#include <unistd.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <random>

#include "fleet/mqtt/broker_config.hpp"

namespace fleet::ctl {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

constexpr const char* kManufacturer = "fleet-sim";

std::string randomPassword(std::mt19937_64& rng) {
  static const char* const kChars = "abcdefghijkmnpqrstuvwxyzACDEFGHJKLMNPQRSTUVWXYZ23456789";
  std::string s;
  for (int i = 0; i < 20; ++i) {
    s += kChars[rng() % 55];
  }
  return s;
}

bool runAndWait(const std::string& exe, const std::vector<std::string>& args) {
  const pid_t pid = fork();
  if (pid < 0) {
    return false;
  }
  if (pid == 0) {
    std::vector<char*> argv{const_cast<char*>(exe.c_str())};
    for (const auto& a : args) {
      argv.push_back(const_cast<char*>(a.c_str()));
    }
    argv.push_back(nullptr);
    execv(exe.c_str(), argv.data());
    _exit(127);
  }
  int status = 0;
  return waitpid(pid, &status, 0) == pid && WIFEXITED(status) && WEXITSTATUS(status) == 0;
}

bool write(const fs::path& p, const std::string& text) {
  std::ofstream f(p);
  f << text;
  return static_cast<bool>(f);
}

}  // namespace

Expected<void> writeVda5050Files(const Vda5050Files& f) {
  std::mt19937_64 rng(std::random_device{}());
  const fs::path seen = f.seen_at.empty() ? fs::absolute(f.out) : f.seen_at;
  mqtt::BrokerConfig c;
  c.port = f.port;
  c.bind_address = f.bind_address;
  c.password_file = (seen / "mosquitto.passwd").string();
  c.acl_file = (seen / "mosquitto.acl").string();
  if (f.log_to_file) {
    c.log_file = (seen / "mosquitto.log").string();
  }
  if (::getuid() == 0 && f.seen_at.empty()) {
    c.run_as_user = "root";  // the files are root's and private
  }
  const std::string master_password = randomPassword(rng);
  c.users.push_back({"master", master_password, {"uagv/#"}});
  json vehicles = json::array();
  json bridge_vehicles = json::array();
  for (const auto& r : f.robots) {
    const std::string pw = randomPassword(rng);
    c.users.push_back({std::string(kManufacturer) + "-" + r,
                       pw,
                       {std::string("uagv/v2/") + kManufacturer + "/" + r + "/#"}});
    vehicles.push_back({{"robot", r}, {"password", pw}});
    bridge_vehicles.push_back({{"manufacturer", kManufacturer}, {"serial", r}, {"robot", r}});
  }
  const auto passwd = f.out / "mosquitto.passwd";
  if (!write(f.out / "mosquitto.conf", mqtt::mosquittoConf(c)) ||
      !write(f.out / "mosquitto.acl", mqtt::aclText(c)) || !write(passwd, "")) {
    return unexpected("vda5050.files", "cannot write the broker's files under " + f.out.string());
  }
  fs::permissions(passwd, fs::perms::owner_read | fs::perms::owner_write);
  for (const auto& u : c.users) {
    if (!runAndWait("/usr/bin/mosquitto_passwd", {"-b", passwd.string(), u.name, u.password})) {
      return unexpected("vda5050.files",
                        "mosquitto_passwd failed for " + u.name + " (is mosquitto installed?)");
    }
  }
  json broker{{"port", f.port}};
  if (f.broker_host != "127.0.0.1") {
    broker["host"] = f.broker_host;
  }
  json master = broker;
  master["username"] = "master";
  master["password"] = master_password;
  if (!write(f.out / "vda5050_vehicles.json",
             json{{"broker", broker}, {"map_id", f.map_id}, {"vehicles", vehicles}}.dump(1)) ||
      !write(f.out / "vda5050_bridge.json", json{{"broker", master},
                                                 {"map_id", f.map_id},
                                                 {"clock", f.sim_clock ? "sim" : "wall"},
                                                 {"lockstep", f.sim_clock},
                                                 {"vehicles", bridge_vehicles}}
                                                .dump(1))) {
    return unexpected("vda5050.files", "cannot write the VDA 5050 files under " + f.out.string());
  }
  return {};
}

Expected<Vda5050Run> prepareVda5050(const fs::path& out, const std::vector<std::string>& robots,
                                    const std::string& map_id, int port, const std::string& bridge_exe,
                                    const std::vector<std::pair<std::string, std::string>>& env,
                                    bool sim_clock) {
  Vda5050Files files;
  files.out = fs::absolute(out);
  files.robots = robots;
  files.map_id = map_id;
  files.port = port;
  files.sim_clock = sim_clock;
  if (auto written = writeVda5050Files(files); !written) {
    return unexpected("loadtest.vda5050", written.error().message);
  }
  Vda5050Run run;
  run.vehicles_file = files.out / "vda5050_vehicles.json";
  run.broker = {"mosquitto",
                "/usr/sbin/mosquitto",
                {"-c", (files.out / "mosquitto.conf").string()},
                env,
                (files.out / "mosquitto.stderr.log").string()};
  run.bridge = {"vda5050_bridge",
                bridge_exe,
                {"--config", (files.out / "vda5050_bridge.json").string(), "--log-level", "info"},
                env,
                (files.out / "vda5050_bridge.log").string()};
  return run;
}

}  // namespace fleet::ctl
