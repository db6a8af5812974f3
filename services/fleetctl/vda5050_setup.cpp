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

Expected<Vda5050Run> prepareVda5050(const fs::path& out, const std::vector<std::string>& robots,
                                    const std::string& map_id, int port, const std::string& bridge_exe,
                                    const std::vector<std::pair<std::string, std::string>>& env,
                                    bool sim_clock) {
  std::mt19937_64 rng(std::random_device{}());
  mqtt::BrokerConfig c;
  c.port = port;
  c.password_file = fs::absolute(out / "mosquitto.passwd").string();
  c.acl_file = fs::absolute(out / "mosquitto.acl").string();
  c.log_file = fs::absolute(out / "mosquitto.log").string();
  if (::getuid() == 0) {
    c.run_as_user = "root";  // the files are root's and private
  }
  const std::string master_password = randomPassword(rng);
  c.users.push_back({"master", master_password, {"uagv/#"}});
  json vehicles = json::array();
  json bridge_vehicles = json::array();
  for (const auto& r : robots) {
    const std::string pw = randomPassword(rng);
    c.users.push_back({std::string(kManufacturer) + "-" + r,
                       pw,
                       {std::string("uagv/v2/") + kManufacturer + "/" + r + "/#"}});
    vehicles.push_back({{"robot", r}, {"password", pw}});
    bridge_vehicles.push_back({{"manufacturer", kManufacturer}, {"serial", r}, {"robot", r}});
  }
  const auto conf = out / "mosquitto.conf";
  if (!write(conf, mqtt::mosquittoConf(c)) || !write(c.acl_file, mqtt::aclText(c)) ||
      !write(c.password_file, "")) {
    return unexpected("loadtest.vda5050", "cannot write the broker's files under " + out.string());
  }
  fs::permissions(c.password_file, fs::perms::owner_read | fs::perms::owner_write);
  for (const auto& u : c.users) {
    if (!runAndWait("/usr/bin/mosquitto_passwd", {"-b", c.password_file, u.name, u.password})) {
      return unexpected("loadtest.vda5050",
                        "mosquitto_passwd failed for " + u.name + " (is mosquitto installed?)");
    }
  }
  Vda5050Run run;
  run.vehicles_file = fs::absolute(out / "vda5050_vehicles.json");
  const auto bridge_conf = fs::absolute(out / "vda5050_bridge.json");
  if (!write(run.vehicles_file,
             json{{"broker", {{"port", port}}}, {"map_id", map_id}, {"vehicles", vehicles}}.dump(1)) ||
      !write(bridge_conf,
             json{{"broker", {{"port", port}, {"username", "master"}, {"password", master_password}}},
                  {"map_id", map_id},
                  {"clock", sim_clock ? "sim" : "wall"},
                  {"lockstep", sim_clock},
                  {"vehicles", bridge_vehicles}}
                 .dump(1))) {
    return unexpected("loadtest.vda5050", "cannot write the VDA 5050 files under " + out.string());
  }
  run.broker = {"mosquitto",
                "/usr/sbin/mosquitto",
                {"-c", fs::absolute(conf).string()},
                env,
                fs::absolute(out / "mosquitto.stderr.log").string()};
  run.bridge = {"vda5050_bridge",
                bridge_exe,
                {"--config", bridge_conf.string(), "--log-level", "info"},
                env,
                fs::absolute(out / "vda5050_bridge.log").string()};
  return run;
}

}  // namespace fleet::ctl
