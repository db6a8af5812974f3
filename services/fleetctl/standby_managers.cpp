#include "standby_managers.hpp"

#include <httplib.h>

#include <chrono>
#include <cstdio>

#include "fleet/pgserver/postgres_server.hpp"

namespace fleet::ctl {
namespace {

using Clock = std::chrono::steady_clock;

bool ready(int port) {
  httplib::Client c("127.0.0.1", port);
  c.set_connection_timeout(0, 300000);
  c.set_read_timeout(1, 0);
  auto r = c.Get("/readyz");
  return r && r->status == 200;
}

}  // namespace

StandbyManagers::StandbyManagers(const std::filesystem::path& runDir, const std::string& binDir) {
  pgserver::PostgresServer::Options o;
  o.templateDir = std::filesystem::path(binDir) / "pg-template";
  o.dir = runDir / "postgres";
  o.durable = true;  // acknowledged = on disk, as in production
  server_ = std::make_unique<pgserver::PostgresServer>(o);
}

StandbyManagers::~StandbyManagers() {
  settle();
}

bool StandbyManagers::ok() const {
  return server_->ok();
}

std::string StandbyManagers::error() const {
  return server_->error();
}

std::string StandbyManagers::url() const {
  return server_->url();
}

std::vector<ProcessSpec> StandbyManagers::specs(const ProcessSpec& manager, int opsPort, int standbyOpsPort) {
  ports_[0] = opsPort;
  ports_[1] = standbyOpsPort;
  std::vector<ProcessSpec> out;
  for (int i = 0; i < 2; ++i) {
    ProcessSpec s = manager;
    s.name = i == 0 ? kFirst : kSecond;
    s.args.insert(s.args.end(), {"--store", url(), "--metrics-port", std::to_string(ports_[i])});
    if (i == 1) {
      const auto dot = s.log.rfind(".log");
      s.log = s.log.substr(0, dot) + "_2.log";
    }
    out.push_back(std::move(s));
  }
  return out;
}

int StandbyManagers::opsPortOf(const std::string& name) const {
  return name == kFirst ? ports_[0] : ports_[1];
}

std::string StandbyManagers::active() const {
  for (const char* name : {kFirst, kSecond}) {
    if (ready(opsPortOf(name))) {
      return name;
    }
  }
  return "";
}

std::string StandbyManagers::killActive(Supervisor& sup) {
  settle();
  const std::string killed = active();
  if (killed.empty()) {
    return "";
  }
  sup.killHard(killed);
  const auto at = Clock::now();
  timer_ = std::thread([this, killed, at] {
    // Until either is ready: the standby, or the killed one restarted (by a fault's +D shorter than
    // the takeover, it may win the expired lease).
    nlohmann::json t{{"killed", killed}};
    std::string by;
    while ((by = active()).empty()) {
      if (Clock::now() - at > std::chrono::seconds(30)) {
        t["error"] = "no manager active within 30 s";
        break;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    if (!by.empty()) {
      t["by"] = by;
      t["took_s"] = std::chrono::duration<double>(Clock::now() - at).count();
    }
    std::lock_guard<std::mutex> lock(mu_);
    takeovers_.push_back(std::move(t));
  });
  return killed;
}

void StandbyManagers::settle() {
  if (timer_.joinable()) {
    timer_.join();
  }
}

void StandbyManagers::stop(Supervisor& sup, double graceS) {
  settle();
  const bool firstActive = active() == kFirst;
  sup.stop(firstActive ? kSecond : kFirst, graceS);
  sup.stop(firstActive ? kFirst : kSecond, graceS);
}

nlohmann::json StandbyManagers::reportJson() {
  settle();
  std::lock_guard<std::mutex> lock(mu_);
  std::vector<double> took;
  int failed = 0;
  for (const auto& t : takeovers_) {
    if (t.contains("took_s")) {
      took.push_back(t["took_s"].get<double>());
    } else {
      ++failed;
    }
  }
  return {{"backend", "postgresql"},
          {"managers", 2},
          {"takeovers", takeovers_},
          {"takeovers_failed", failed},
          {"takeover_s", toJson(percentiles(took))}};
}

std::string StandbyManagers::summaryLine() {
  const auto r = reportJson();
  const auto& p = r["takeover_s"];
  int byStandby = 0;
  for (const auto& t : r["takeovers"]) {
    byStandby += t.contains("by") && t["by"] != t["killed"] ? 1 : 0;
  }
  char line[240];
  std::snprintf(
      line, sizeof line,
      "store postgresql, 2 managers: %zu kill(s) of the active one; a manager active again after p50 "
      "%.2f s max %.2f s (%d times the standby, else the killed one restarted); %d not within 30 s",
      r["takeovers"].size(), p.value("p50", 0.0), p.value("max", 0.0), byStandby,
      r.value("takeovers_failed", 0));
  return line;
}

}  // namespace fleet::ctl
