#include "loadtest.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <httplib.h>
#include <netinet/in.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <mutex>
#include <random>
#include <set>
#include <sstream>
#include <thread>
#include <tuple>

#include "base_ends.hpp"
#include "fault_plan.hpp"
#include "fleet/core/config.hpp"
#include "fleet/fleet/site_stations.hpp"
#include "fleet/transport/dds.hpp"
#include "run_bounds.hpp"
#include "run_figures.hpp"
#include "saturation.hpp"
#include "scenario_gen.hpp"
#include "scenario_tasks.hpp"
#include "standby_managers.hpp"
#include "store_contents.hpp"
#include "supervisor.hpp"
#include "task_ledger.hpp"
#include "vda5050_setup.hpp"

namespace fleet::ctl {
namespace {

// A DDS domain no other run on this machine uses: two fleets on one domain take each other's
// orders (robots are keyed by id, and every fleet has an r1). Runs and tests hold a lock file per
// domain for their lifetime (the convention of tests/support/test_process.hpp); the lock is
// released when this process ends.
int lockFreeDomain() {
  const int start = static_cast<int>(std::random_device{}() % 120);
  for (int k = 0; k < 120; ++k) {
    const int d = 100 + (start + k) % 120;
    const std::string path = "/tmp/fleet-test-dds-domain-" + std::to_string(d) + ".lock";
    const int fd = open(path.c_str(), O_CREAT | O_RDWR | O_CLOEXEC, 0666);
    if (fd >= 0 && flock(fd, LOCK_EX | LOCK_NB) == 0) {
      return d;  // fd stays open: the lock lives as long as the process
    }
    if (fd >= 0) {
      close(fd);
    }
  }
  return 100 + start;
}

namespace fs = std::filesystem;
using nlohmann::json;
using Clock = std::chrono::steady_clock;

std::atomic<int> gSignal{0};
extern "C" void onSignal(int sig) {
  gSignal = sig;
}

void say(const std::string& s) {
  std::cout << "loadtest: " << s << std::endl;
}

int freePort() {
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  a.sin_port = 0;
  socklen_t len = sizeof a;
  int port = 0;
  if (bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0 &&
      getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len) == 0) {
    port = ntohs(a.sin_port);
  }
  close(fd);
  return port;
}

bool writeFile(const fs::path& p, const std::string& text) {
  std::ofstream out(p);
  out << text;
  return static_cast<bool>(out);
}

std::optional<json> readJson(const fs::path& p) {
  std::ifstream in(p);
  if (!in) {
    return std::nullopt;
  }
  auto j = json::parse(in, nullptr, false);
  if (j.is_discarded()) {
    return std::nullopt;
  }
  return j;
}

/// The loopback Cyclone configuration of deploy/cyclonedds-local.xml, plus Cyclone's own packet
/// dropper (Internal/Test/XmitLossiness, per mille of outgoing packets) for the drop-dds fault.
std::string cycloneConfig(double drop) {
  return transport::loopbackConfig(false, static_cast<int>(std::lround(drop * 1000.0))) + "\n";
}

struct Run {
  LoadtestOptions o;  // a copy
  Supervisor sup;
  fs::path out;
  json scenario;
  std::vector<std::string> agentNames;
  std::map<std::string, std::string> agentOfRobot;
  std::string vdaVehiclesFile;  // fleet-sim --vda5050; empty: no VDA 5050 vehicles
  std::vector<Fault> faults;
  std::vector<bool> faultStarted, faultEnded;
  std::vector<Clock::time_point> faultEndAt;
  std::vector<std::string> faultTarget;  // the process a kill fault killed (restarted D s later)
  json faultLog = json::array();
  TaskLedger ledger;
  std::vector<json> pending;            // generated or due from the list, not acknowledged yet
  int generated = 0;                    // tasks handed to the poster (generated or from the list)
  bool fromList = false;                // posting the scenario's task list instead of generating
  std::vector<ScenarioTask> listTasks;  // the scenario's task list, by at_s (stable)
  std::size_t listNext = 0;             // first task of listTasks not posted yet
  int untilDoneTarget = 0;              // --until-done: stop once this many tasks are finished
  int refused = 0;
  int postErrors = 0;
  std::vector<std::string> pickups, dropoffs;
  std::mt19937_64 rng;
  double simS = 0;
  double firstStampS = 0;                     // wall clock: the first robot stamp seen
  std::unique_ptr<httplib::Client> http;      // progress and sim time (main thread)
  std::unique_ptr<httplib::Client> postHttp;  // task submission (poster thread)
  std::mutex mu;                              // pending, ledger, counters
  std::atomic<bool> stopPosting{false};
  ProcessSpec managerSpec;
  std::unique_ptr<StandbyManagers> standby;  // --store postgresql: the database and two managers

  explicit Run(const LoadtestOptions& opt) : o(opt), rng(opt.seed) {}

  std::string bin(const std::string& rel) const { return (fs::path(o.binDir) / rel).string(); }

  void logFault(const std::string& what) {
    faultLog.push_back({{"sim_s", simS}, {"event", what}});
    say("fault: " + what);
  }

  /// Tasks per simulated minute: the option, 0.75 per robot, or the task list's average rate.
  double ratePerMin() const {
    if (fromList) {
      return o.durationS > 0 ? static_cast<double>(untilDoneTarget) * 60.0 / o.durationS : 0.0;
    }
    return o.ratePerMin > 0 ? o.ratePerMin : 0.75 * static_cast<double>(scenario["robots"].size());
  }

  /// The scenario's tasks whose at_s the simulated clock has reached go to the poster (those at or
  /// after the end never: whether the clock is seen there before the simulator stops is a race).
  void listDue() {
    std::lock_guard<std::mutex> lock(mu);
    while (listNext < listTasks.size() && listTasks[listNext].atS <= simS &&
           listTasks[listNext].atS < o.durationS) {
      pending.push_back(toTaskRequest(listTasks[listNext]));
      ++listNext;
      ++generated;
    }
  }

  void generateDue() {
    if (fromList) {
      listDue();
      return;
    }
    const double rate =
        o.ratePerMin > 0 ? o.ratePerMin : 0.75 * static_cast<double>(scenario["robots"].size());
    const int due = static_cast<int>(std::floor(simS * rate / 60.0)) + 1;
    std::lock_guard<std::mutex> lock(mu);
    while (generated < due && (o.maxTasks <= 0 || generated < o.maxTasks)) {
      ++generated;
      char id[32];
      std::snprintf(id, sizeof id, "lt-%05d", generated);
      std::uniform_int_distribution<std::size_t> p(0, pickups.size() - 1);
      std::uniform_int_distribution<std::size_t> d(0, dropoffs.size() - 1);
      pending.push_back({{"id", id},
                         {"kind", "transport"},
                         {"pickup", pickups[p(rng)]},
                         {"dropoff", dropoffs[d(rng)]},
                         {"load_duration_ns", 2000000000LL},
                         {"unload_duration_ns", 2000000000LL}});
    }
  }

  /// Posts what is pending; acknowledged ids go to the ledger, refused ones are dropped (counted),
  /// unavailable ones stay pending and are re-sent (ids are idempotency keys).
  void submitPending() {
    std::vector<json> toPost;
    {
      std::lock_guard<std::mutex> lock(mu);
      toPost.swap(pending);
    }
    if (toPost.empty()) {
      return;
    }
    std::vector<json> keep;
    for (std::size_t i = 0; i < toPost.size(); i += 100) {
      json batch = json::array();
      for (std::size_t k = i; k < std::min(toPost.size(), i + 100); ++k) {
        batch.push_back(toPost[k]);
      }
      auto r = postHttp->Post("/v1/tasks", batch.dump(), "application/json");
      if (!r) {
        ++postErrors;
        for (auto& t : batch) {
          keep.push_back(t);
        }
        continue;
      }
      auto body = json::parse(r->body, nullptr, false);
      json results = json::array();
      if (body.is_object() && body.contains("results")) {
        results = body["results"];
      } else if (body.is_object() && body.contains("id")) {
        results.push_back(body);
      }
      std::set<std::string> answered;
      for (const auto& item : results) {
        const std::string id = item.value("id", "");
        const int st = item.value("status", 0);
        answered.insert(id);
        if (st == 200 || st == 201) {
          std::lock_guard<std::mutex> lock(mu);
          ledger.acknowledged(id);
        } else if (st >= 400 && st < 500 && st != 429) {
          ++refused;
          say("task " + id + " refused: " + item.dump());
        } else {
          for (auto& t : batch) {
            if (t["id"] == id) {
              keep.push_back(t);
            }
          }
        }
      }
      for (auto& t : batch) {
        if (!answered.count(t["id"].get<std::string>())) {
          keep.push_back(t);
        }
      }
    }
    std::lock_guard<std::mutex> lock(mu);
    pending.insert(pending.begin(), keep.begin(), keep.end());
  }

  /// Posting runs on its own thread: a POST waits up to the adapter's acknowledgement timeout
  /// while the manager is down, and faults and progress must not wait for it.
  void postLoop() {
    while (!stopPosting) {
      submitPending();
      std::this_thread::sleep_for(std::chrono::milliseconds(200));
    }
  }

  void pollSimTime() {
    auto r = http->Get("/v1/robots");
    if (!r || r->status != 200) {
      return;
    }
    auto body = json::parse(r->body, nullptr, false);
    if (!body.is_object()) {
      return;
    }
    for (const auto& x : body.value("robots", json::array())) {
      const double stampS = static_cast<double>(x.value("stamp_ns", std::int64_t{0})) / 1e9;
      if (o.wallClock) {
        // Stamps are wall-clock epoch times: the simulated time is the time since the first one.
        if (stampS > 0 && firstStampS == 0) {
          firstStampS = stampS;
        }
        simS = std::max(simS, stampS - firstStampS);
      } else {
        simS = std::max(simS, stampS);
      }
    }
  }

  std::string agentFor(const Fault& f) const {
    if (f.kind == Fault::Kind::StallRobot) {
      auto it = agentOfRobot.find(f.robot);
      return it == agentOfRobot.end() ? "" : it->second;
    }
    return "agent-" + std::to_string(f.agent);
  }

  void applyFaults() {
    const auto now = Clock::now();
    for (std::size_t i = 0; i < faults.size(); ++i) {
      const Fault& f = faults[i];
      if (f.kind == Fault::Kind::DropDds) {
        continue;
      }
      if (f.kind == Fault::Kind::HideLandmarks) {
        // The simulator hides them on its own clock (--hide-landmarks): only logged here.
        if (!faultStarted[i] && simS >= f.atS) {
          faultStarted[i] = true;
          logFault("landmarks hidden (fleet-sim) for " + std::to_string(static_cast<int>(f.downS)) + " s");
        } else if (faultStarted[i] && !faultEnded[i] && simS >= f.atS + f.downS) {
          faultEnded[i] = true;
          logFault("landmarks visible again");
        }
        continue;
      }
      if (f.kind == Fault::Kind::CloseArea) {
        // Through the API an operator would use; on the simulated clock, as hide-landmarks.
        const std::string path = "/v1/traffic/closures/fault-" + std::to_string(i);
        if (!faultStarted[i] && simS >= f.atS) {
          faultStarted[i] = true;
          json body = {{"area", json::array()},
                       {"reason", ("load test fault " + describe(f)).substr(0, 255)}};
          for (std::size_t k = 0; k + 1 < f.area.size(); k += 2) {
            body["area"].push_back({f.area[k], f.area[k + 1]});
          }
          auto r = http->Put(path, body.dump(), "application/json");
          logFault("closed area fault-" + std::to_string(i) + ": " +
                   (r ? std::to_string(r->status) + " " + r->body : std::string("adapter unreachable")));
        } else if (faultStarted[i] && !faultEnded[i] && simS >= f.atS + f.downS) {
          faultEnded[i] = true;
          auto r = http->Delete(path);
          logFault("reopened area fault-" + std::to_string(i) + ": " +
                   (r ? std::to_string(r->status) : std::string("adapter unreachable")));
        }
        continue;
      }
      std::string& who = faultTarget[i];
      if (!faultStarted[i] && simS >= f.atS) {
        faultStarted[i] = true;
        faultEndAt[i] =
            now + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(f.downS));
        who = killedService(f).empty() ? agentFor(f) : killedService(f);
        if (f.kind == Fault::Kind::StallRobot) {
          sup.signal(who, SIGSTOP);
          logFault("SIGSTOP " + who + " (robot " + f.robot + ")");
        } else if (f.kind == Fault::Kind::KillManager && standby) {
          // Two managers: the active one is killed, the standby takes over (timed).
          who = standby->killActive(sup);
          logFault(who.empty() ? std::string("no active fleet manager to kill")
                               : "SIGKILL " + who + " (active)");
        } else {
          sup.killHard(who);
          logFault("SIGKILL " + who);
        }
      } else if (faultStarted[i] && !faultEnded[i] && now >= faultEndAt[i]) {
        faultEnded[i] = true;
        if (f.kind == Fault::Kind::StallRobot) {
          sup.signal(who, SIGCONT);
          logFault("SIGCONT " + who);
        } else if (!who.empty()) {
          sup.restart(who);
          logFault("restarted " + who);
        }
      }
    }
  }

  /// Tasks the manager holds in a final state (done, failed, cancelled), from the adapter's metrics.
  std::size_t finishedTasks() {
    std::size_t n = 0;
    if (auto r = http->Get("/v1/metrics"); r && r->status == 200) {
      auto m = json::parse(r->body, nullptr, false);
      if (m.is_object() && m.contains("tasks_by_state") && m["tasks_by_state"].is_object()) {
        for (const char* k : {"done", "failed", "cancelled"}) {
          if (m["tasks_by_state"].contains(k) && m["tasks_by_state"][k].is_number_unsigned()) {
            n += m["tasks_by_state"][k].get<std::size_t>();
          }
        }
      }
    }
    return n;
  }

  std::string progressLine(double wallS) {
    std::string states;
    if (auto r = http->Get("/v1/metrics"); r && r->status == 200) {
      auto m = json::parse(r->body, nullptr, false);
      if (m.is_object() && m.contains("tasks_by_state")) {
        for (const auto& [k, v] : m["tasks_by_state"].items()) {
          states += " " + k + "=" + v.dump();
        }
      }
    }
    char buf[160];
    std::snprintf(buf, sizeof buf, "%5.0f s wall | %6.1f s sim (%.2fx) | acknowledged %zu pending %zu |",
                  wallS, simS, wallS > 0 ? simS / wallS : 0.0, ledger.count(), pending.size());
    return buf + states;
  }

  int run();
  /// --serve: the adapter (kept running, on `port`) and the report's files on loopback until Ctrl-C.
  void serveUntilInterrupted(int port);
};

int Run::run() {
  out = o.out;
  std::error_code ec;
  fs::create_directories(out, ec);
  if (ec) {
    say("cannot create " + out.string() + ": " + ec.message());
    return 1;
  }
  auto parsed = parseFaults(o.faults);
  if (!parsed) {
    std::cerr << "fleetctl loadtest: " << parsed.error().message << "\n";
    return 2;
  }
  faults = *parsed;
  faultStarted.assign(faults.size(), false);
  faultEnded.assign(faults.size(), false);
  faultEndAt.assign(faults.size(), Clock::now());
  faultTarget.assign(faults.size(), "");

  // The scenario: a file as is, or one generated for the fleet size.
  fs::path scenarioPath = out / "scenario.json";
  if (!o.scenario.empty()) {
    auto s = readJson(o.scenario);
    if (!s) {
      std::cerr << "fleetctl loadtest: " << o.scenario << ": cannot read a JSON scenario\n";
      return 2;
    }
    scenario = *s;
    scenario["duration_s"] = o.durationS;
    // Its task list, checked here so that every problem is reported before anything starts.
    try {
      scenario = resolveScenarioSite(std::move(scenario), o.scenario);
      if (auto list = parseScenarioTasks(scenario, o.scenario)) {
        listTasks = std::move(*list);
        fromList = !o.generateTasks;
      }
    } catch (const ConfigError& e) {
      std::cerr << "fleetctl loadtest: " << e.what() << "\n";
      return 2;
    }
    std::stable_sort(listTasks.begin(), listTasks.end(),
                     [](const ScenarioTask& a, const ScenarioTask& b) { return a.atS < b.atS; });
  } else {
    auto t = readJson(o.templ);
    if (!t) {
      std::cerr << "fleetctl loadtest: " << o.templ << ": cannot read the scenario template\n";
      return 2;
    }
    // A generated scenario carries its own map and stations; the template gives the rest, and its
    // site the robot description.
    if (t->contains("site")) {
      try {
        *t = inlineSiteRobot(*t, o.templ);
      } catch (const ConfigError& e) {
        std::cerr << "fleetctl loadtest: " << e.what() << "\n";
        return 2;
      }
    }
    auto g = generateScenario(*t, {o.robots, o.humans, o.durationS, o.seed, o.siteRobots});
    if (!g) {
      std::cerr << "fleetctl loadtest: " << g.error().message << "\n";
      return 2;
    }
    // Its map and stations become the run's site, so every service reads a site as in production.
    auto [site, rest] = splitSite(*g);
    writeFile(out / "site.json", site.dump(1));
    rest["site"] = fs::absolute(out / "site.json").string();
    scenario = resolveScenarioSite(rest, (out / "scenario.json").string());
  }
  // A relative map file stays relative to the original scenario's folder.
  if (!o.scenario.empty() && scenario.contains("map") && scenario["map"].is_object() &&
      scenario["map"].contains("file")) {
    scenario["map"]["file"] =
        (fs::absolute(o.scenario).parent_path() / scenario["map"]["file"].get<std::string>()).string();
  }
  {
    json forRun = scenario;
    forRun.erase("site_stations");  // fleetctl's own copy of the site's stations
    writeFile(scenarioPath, forRun.dump(1));
  }
  for (const auto& s : scenarioStations(scenario)) {
    if (s.value("kind", "") == "pickup") {
      pickups.push_back(s["name"]);
    } else if (s.value("kind", "") == "dropoff") {
      dropoffs.push_back(s["name"]);
    }
  }
  if (pickups.empty() || dropoffs.empty()) {
    std::cerr << "fleetctl loadtest: the scenario has no pickup or no dropoff station\n";
    return 2;
  }
  std::vector<std::string> robots;
  for (const auto& r : scenario.value("robots", json::array())) {
    robots.push_back(r.value("id", ""));
  }
  for (const auto& f : faults) {
    if (f.kind == Fault::Kind::StallRobot &&
        std::find(robots.begin(), robots.end(), f.robot) == robots.end()) {
      std::cerr << "fleetctl loadtest: --fault stall:" << f.robot << ": the scenario has no robot '"
                << f.robot << "'\n";
      return 2;
    }
    if (f.kind == Fault::Kind::KillAgent && f.agent >= o.agents) {
      std::cerr << "fleetctl loadtest: --fault " << describe(f) << ": there are only " << o.agents
                << " agent process(es) (--agents)\n";
      return 2;
    }
  }

  // Processes: configuration files, DDS settings, then start in dependency order.
  const int port = o.port > 0 ? o.port : freePort();
  int domain = o.domain;
  if (domain < 0) {
    const char* env = std::getenv("FLEET_DDS_DOMAIN");
    domain = env ? std::atoi(env) : lockFreeDomain();
  }
  std::vector<std::pair<std::string, std::string>> env = {{"FLEET_DDS_DOMAIN", std::to_string(domain)}};
  const double drop = dropFraction(faults);
  // DDS Security: each process joins as its identity of the folder (scripts/dds-security).
  const auto identityOf = [](const std::string& process) -> std::string {
    if (process.rfind("agent-", 0) == 0) {
      return process;  // made for this run with its robots (below)
    }
    static const std::map<std::string, std::string> kIdentity = {{"fleet_manager", "fleet-manager"},
                                                                 {"fleet_manager_2", "fleet-manager"},
                                                                 {"vda5050_bridge", "vda5050-bridge"},
                                                                 {"wms_adapter", "wms-adapter"},
                                                                 {"risk_map", "risk-map"},
                                                                 {"traffic_manager", "traffic-manager"},
                                                                 {"fleet-sim", "simulator"}};
    const auto it = kIdentity.find(process);
    return it == kIdentity.end() ? process : it->second;
  };
  if (!o.ddsSecurity.empty()) {
    if (drop > 0) {
      std::cerr << "fleetctl loadtest: --dds-security and a drop-packets fault both need their own "
                   "CYCLONEDDS_URI; give one of them\n";
      return 2;
    }
    std::vector<std::string> missing;
    for (const char* id : {"fleet-manager", "wms-adapter", "risk-map", "traffic-manager", "simulator"}) {
      if (!fs::exists(fs::path(o.ddsSecurity) / id / "cyclonedds.xml")) {
        missing.emplace_back(id);
      }
    }
    if (!fs::exists(fs::path(o.ddsSecurity) / "ca.key")) {
      missing.emplace_back("the agent processes (the site CA's key ca.key is not there to make them)");
    }
    if (!missing.empty()) {
      std::string names;
      for (const auto& m : missing) {
        names += (names.empty() ? "" : ", ") + m;
      }
      std::cerr << "fleetctl loadtest: --dds-security " << o.ddsSecurity << ": no identity for " << names
                << " (make them with: scripts/dds-security deployment " << o.ddsSecurity << " agents)\n";
      return 2;
    }
  }
  const auto secure = [&](ProcessSpec& s) {
    if (!o.ddsSecurity.empty()) {
      s.env.emplace_back(
          "CYCLONEDDS_URI",
          "file://" + fs::absolute(fs::path(o.ddsSecurity) / identityOf(s.name) / "cyclonedds.xml").string());
    }
  };
  if (drop > 0) {
    writeFile(out / "cyclonedds.xml", cycloneConfig(drop));
    env.emplace_back("CYCLONEDDS_URI", "file://" + fs::absolute(out / "cyclonedds.xml").string());
  }
  auto [wM, hM] = mapExtent(scenario);
  // The site every other service reads; the risk map lays its grid over the same site's map.
  const std::string siteFile =
      scenario.contains("site") && scenario["site"].is_string() ? scenario["site"].get<std::string>() : "";
  if (!siteFile.empty()) {
    auto site = fleet::loadSiteFile(siteFile);
    if (!site) {
      std::cerr << "fleetctl loadtest: " << site.error().message << "\n";
      return 2;
    }
    wM = site->map.width() * site->map.resolution();
    hM = site->map.height() * site->map.resolution();
  }
  if (wM <= 0) {
    wM = 100;
    hM = 50;
  }
  // 0.1 m cells up to ~1.2 M cells, coarser beyond (the fusion cost grows with the cell count).
  const double res = wM * hM / 0.01 <= 1.2e6 ? 0.1 : (wM * hM / 0.04 <= 1.2e6 ? 0.2 : 0.25);
  const fs::path db = out / "fleet.db";
  fs::remove(db, ec);
  fs::remove(out / "fleet.db-wal", ec);
  fs::remove(out / "fleet.db-shm", ec);
  fs::remove(out / "traffic_manager_summary.json", ec);  // not a previous run's
  writeFile(out / "manager.json",
            json{{"stations", fs::absolute(scenarioPath).string()},
                 {"db", fs::absolute(db).string()},
                 {"clock", "sim"},
                 {"lease_s", 3.0},
                 {"station_capacity", o.stationCapacity == "queue" ? json(o.stationCapacity)
                                                                   : json(std::stoi(o.stationCapacity))},
                 {"station_load", o.stationLoad},
                 {"travel_cost", o.travelCost},
                 {"metrics_file", fs::absolute(out / "manager_metrics.json").string()}}
                .dump(1));
  {
    json riskMap = {{"clock", "sim"}, {"lockstep", !o.wallClock}, {"rate_hz", 2}};
    if (!siteFile.empty()) {
      // The site gives the grid's origin and extent (a ROS map's origin need not be 0, 0).
      riskMap["site"] = siteFile;
      riskMap["grid"] = {{"resolution", res}};
    } else {
      riskMap["grid"] = {
          {"width", static_cast<int>(wM / res)}, {"height", static_cast<int>(hM / res)}, {"resolution", res}};
    }
    writeFile(out / "risk_map.json", riskMap.dump(1));
  }
  const std::string scn = fs::absolute(scenarioPath).string();
  auto log = [&](const std::string& name) { return fs::absolute(out / (name + ".log")).string(); };
  managerSpec = {"fleet_manager",
                 bin("services/fleet_manager/fleet_manager"),
                 {"--config", fs::absolute(out / "manager.json").string(), "--log-level", "warn"},
                 env,
                 log("fleet_manager")};
  if (o.store == "postgresql") {
    standby = std::make_unique<StandbyManagers>(out, o.binDir);
    if (!standby->ok()) {
      say("cannot start PostgreSQL for --store postgresql: " + standby->error());
      return 1;
    }
    say("store: PostgreSQL of the run's own at " + standby->url() + ", two fleet managers on it");
  }
  std::vector<ProcessSpec> specs = {
      managerSpec,
      {"wms_adapter",
       bin("services/wms_adapter/wms_adapter"),
       {"--stations", scn, "--port", std::to_string(port), "--log-level", "warn"},
       env,
       log("wms_adapter")},
      {"risk_map",
       bin("services/risk_map/risk_map"),
       // At info: its one start-up line names the site and the grid laid over it.
       {"--config", fs::absolute(out / "risk_map.json").string(), "--id", "risk_map", "--log-level", "info"},
       env,
       log("risk_map")}};
  if (standby) {
    auto two = standby->specs(managerSpec, freePort(), freePort());
    specs.front() = two[0];
    specs.insert(specs.begin() + 1, two[1]);
  }
  const bool hasSite = scenario.contains("site") && scenario["site"].is_string();
  if (!hasSite) {
    // Every robot drives what the traffic manager releases, on the roadmap it builds from the site.
    std::cerr << "fleetctl loadtest: the scenario names no site (\"site\"): the traffic manager needs one "
                 "for its roadmap\n";
    return 2;
  }
  {
    json tm{{"site", scenario["site"].get<std::string>()},
            {"clock", "sim"},
            {"lockstep", !o.wallClock},
            {"seed", o.seed}};
    if (o.letPass >= 0)
      tm["let_pass"] = o.letPass;
    if (o.yieldAfterS >= 0.0)
      tm["yield_after_s"] = o.yieldAfterS;
    tm["summary_file"] = fs::absolute(out / "traffic_manager_summary.json").string();
    writeFile(out / "traffic_manager.json", tm.dump(1));
    specs.push_back({"traffic_manager",
                     bin("services/traffic_manager/traffic_manager"),
                     {"--config", fs::absolute(out / "traffic_manager.json").string(), "--id",
                      "traffic_manager", "--log-level", "info"},
                     env,
                     log("traffic_manager")});
  }
  // VDA 5050 vehicles: the last N robots, with a broker and the bridge of their own.
  std::set<std::string> vdaRobots;
  if (o.vda5050 > 0) {
    if (o.vda5050 > static_cast<int>(robots.size())) {
      std::cerr << "fleetctl loadtest: --vda5050 " << o.vda5050 << " needs at most " << robots.size()
                << " robots\n";
      return 2;
    }
    if (!o.wallClock && (o.maxSpeed <= 0.0 || o.maxSpeed > 10.0)) {
      // MQTT runs on the wall clock: at 100x a millisecond in the broker is a tenth of a simulated
      // second, and the vehicles wait for their orders (docs/operator-guide.md#pod).
      say("warning: --max-speed " +
          (o.maxSpeed <= 0.0 ? std::string("0 (no cap)") : std::to_string(o.maxSpeed)) +
          " with VDA 5050 vehicles: MQTT runs on the wall clock, so above 10x their orders arrive late in "
          "simulated time (stops at base ends, rejected updates); 4 (the default) or 10 keep it small");
    }
    const std::vector<std::string> ids(robots.end() - o.vda5050, robots.end());
    vdaRobots.insert(ids.begin(), ids.end());
    auto site = fleet::loadSiteFile(scenario["site"].get<std::string>());
    auto vda = prepareVda5050(out, ids, site ? site->name : std::string("site"), freePort(),
                              bin("services/vda5050_bridge/vda5050_bridge"), env, !o.wallClock);
    if (!vda) {
      std::cerr << "fleetctl loadtest: " << vda.error().message << "\n";
      return 1;
    }
    specs.insert(specs.begin(), vda->broker);
    specs.push_back(vda->bridge);
    vdaVehiclesFile = vda->vehicles_file.string();
  }
  // Robots: a process of their own for each stalled robot, the rest round robin over --agents.
  std::set<std::string> alone;
  for (const auto& f : faults) {
    if (f.kind == Fault::Kind::StallRobot) {
      alone.insert(f.robot);
    }
  }
  std::vector<std::vector<std::string>> groups(static_cast<std::size_t>(o.agents));
  std::size_t next = 0;
  for (const auto& r : robots) {
    if (vdaRobots.count(r)) {
      continue;
    }
    if (alone.count(r)) {
      agentOfRobot[r] = "agent-" + r;
      continue;
    }
    groups[next % groups.size()].push_back(r);
    agentOfRobot[r] = "agent-" + std::to_string(next % groups.size());
    ++next;
  }
  std::map<std::string, std::vector<std::string>> robotsOfProcess;  // DDS Security identities
  if (!vdaRobots.empty()) {
    robotsOfProcess["vda5050_bridge"].assign(vdaRobots.begin(), vdaRobots.end());
  }
  auto agentSpec = [&](const std::string& name, const std::vector<std::string>& ids) {
    robotsOfProcess[name] = ids;
    fs::remove(out / (name + "_metrics.json"), ec);  // not a previous run's
    std::string list;
    for (const auto& r : ids) {
      list += (list.empty() ? "" : ",") + r;
    }
    std::vector<std::string> args = {"--scenario",
                                     scn,
                                     "--clock",
                                     o.wallClock ? "wall" : "lockstep",
                                     "--metrics",
                                     fs::absolute(out / (name + "_metrics.json")).string(),
                                     "--id",
                                     name,
                                     "--robots",
                                     list,
                                     "--local-planner",
                                     o.localPlanner,
                                     "--return-home",
                                     std::to_string(o.returnHomeS),
                                     "--log-level",
                                     "warn"};
    if (!o.agentConfig.empty()) {
      args.emplace_back("--config");
      args.push_back(fs::absolute(o.agentConfig).string());
    }
    return ProcessSpec{name, bin("services/robot_agent/robot_agent"), args, env, log(name)};
  };
  for (std::size_t g = 0; g < groups.size(); ++g) {
    if (!groups[g].empty()) {
      specs.push_back(agentSpec("agent-" + std::to_string(g), groups[g]));
      agentNames.push_back(specs.back().name);
    }
  }
  for (const auto& r : alone) {
    specs.push_back(agentSpec("agent-" + r, {r}));
    agentNames.push_back(specs.back().name);
  }

  struct sigaction sa {};
  sa.sa_handler = onSignal;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
  sigaction(SIGHUP, &sa, nullptr);

  say("scenario " + scenario.value("name", std::string("?")) + ": " + std::to_string(robots.size()) +
      " robots, " + std::to_string(scenario.value("humans", json::object()).value("count", 0)) + " humans, " +
      std::to_string(static_cast<int>(o.durationS)) + " s simulated (wall limit " +
      std::to_string(static_cast<int>(o.wallLimitS)) + " s), " + std::to_string(agentNames.size()) +
      " agent process(es), DDS domain " + std::to_string(domain) +
      ", WMS API http://127.0.0.1:" + std::to_string(port) + ", run folder " + out.string());
  if (fromList) {
    untilDoneTarget = static_cast<int>(std::count_if(
        listTasks.begin(), listTasks.end(), [&](const ScenarioTask& t) { return t.atS < o.durationS; }));
    std::string note;
    if (untilDoneTarget < static_cast<int>(listTasks.size())) {
      note = " (" + std::to_string(listTasks.size() - static_cast<std::size_t>(untilDoneTarget)) +
             " at or after the end (" + std::to_string(static_cast<int>(o.durationS)) + " s) are not posted)";
    }
    say("tasks: " + std::to_string(listTasks.size()) + " from the scenario's task list" + note);
  } else {
    untilDoneTarget = o.maxTasks;
    char rate[64];
    std::snprintf(rate, sizeof rate, "%g", ratePerMin());
    say(std::string("tasks: generated at ") + rate + " per minute" +
        (o.maxTasks > 0 ? ", at most " + std::to_string(o.maxTasks) : std::string()) +
        (scenario.contains("tasks") ? " (the scenario's task list of " + std::to_string(listTasks.size()) +
                                          " is not used: --rate, --tasks or --generate-tasks)"
                                    : std::string()));
  }
  for (const auto& f : faults) {
    say("fault planned: " + describe(f));
  }
  if (!o.ddsSecurity.empty()) {
    // One identity per agent process (and the bridge) granting exactly its robots' partitions.
    for (const auto& [process, ids] : robotsOfProcess) {
      std::string list;
      for (const auto& r : ids) {
        list += (list.empty() ? "" : ",") + r;
      }
      const std::string role = process == "vda5050_bridge" ? "vda5050-bridge" : "robot-agent";
      const std::string cmd = "'" + o.securityScript + "' identity '" + fs::absolute(o.ddsSecurity).string() +
                              "' '" + identityOf(process) + "' " + role + " --robots '" + list +
                              "' >/dev/null";
      if (std::system(cmd.c_str()) != 0) {
        say("cannot make the DDS Security identity of " + process + ": " + cmd);
        return 2;
      }
    }
  }
  for (auto& s : specs) {
    secure(s);
  }
  for (const auto& s : specs) {
    if (!sup.start(s)) {
      say("cannot start " + s.name);
      return 1;
    }
  }
  http = std::make_unique<httplib::Client>("127.0.0.1", port);
  http->set_connection_timeout(2, 0);
  http->set_read_timeout(10, 0);
  postHttp = std::make_unique<httplib::Client>("127.0.0.1", port);
  postHttp->set_connection_timeout(2, 0);
  postHttp->set_read_timeout(10, 0);
  // The adapter started here inherits FLEET_WMS_TOKEN from this environment and then asks for it
  // on every request; without it the run stalled at "0.0 s sim" on 401s.
  if (const char* token = std::getenv("FLEET_WMS_TOKEN"); token != nullptr && *token != '\0') {
    http->set_bearer_token_auth(token);
    postHttp->set_bearer_token_auth(token);
  }
  const auto t0 = Clock::now();
  auto wall = [&] { return std::chrono::duration<double>(Clock::now() - t0).count(); };
  bool healthy = false;
  while (wall() < 30 && gSignal == 0) {
    if (auto r = http->Get("/v1/health"); r && r->status == 200) {
      healthy = true;
      break;
    }
    if (auto gone = sup.reapUnexpected(); !gone.empty()) {
      say(gone[0].first + " exited with status " + std::to_string(gone[0].second) + " at start; see " +
          log(gone[0].first));
      return 1;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  if (!healthy) {
    say(gSignal ? "interrupted" : "the WMS adapter did not report a healthy fleet manager within 30 s");
    return gSignal ? 130 : 1;
  }
  say("live dashboard: http://127.0.0.1:" + std::to_string(port) + "/dashboard/ (open it in a browser)");
  // The risk map, the agents and the traffic manager: the simulator starts only when all have
  // registered (a traffic manager it does not wait for falls behind the robots).
  const int participants =
      1 + static_cast<int>(agentNames.size()) + 1 + (vdaVehiclesFile.empty() ? 0 : 1);  // the VDA 5050 bridge
  std::vector<std::string> simArgs = {"--scenario",     scn,
                                      "--duration",     std::to_string(o.durationS),
                                      "--replay",       fs::absolute(out / "replay.jsonl.gz").string(),
                                      "--summary",      fs::absolute(out / "sim_summary.json").string(),
                                      "--html",         fs::absolute(out / "viewer.html").string(),
                                      "--localization", fs::absolute(out / "localization.json").string(),
                                      "--log-level",    "warn",
                                      "--clock"};
  for (const auto& f : faults) {
    if (f.kind == Fault::Kind::HideLandmarks) {
      simArgs.insert(simArgs.begin(),
                     {"--hide-landmarks", describe(f).substr(std::string("hide-landmarks@").size())});
    }
  }
  if (!vdaVehiclesFile.empty()) {
    simArgs.insert(simArgs.begin(), {"--vda5050", vdaVehiclesFile});
  }
  if (o.wallClock) {
    simArgs.emplace_back("wall");
  } else {
    for (const std::string& a :
         {std::string("lockstep"), std::string("--participants"), std::to_string(participants),
          std::string("--start-timeout-ms"), std::string("60000"), std::string("--step-timeout-ms"),
          std::to_string(o.stepTimeoutMs), std::string("--max-speed"), std::to_string(o.maxSpeed)}) {
      simArgs.push_back(a);
    }
  }
  ProcessSpec simSpec{"fleet-sim", bin("sim/src/fleet-sim"), simArgs, env, log("fleet-sim")};
  secure(simSpec);
  sup.start(simSpec);

  int code = 0;
  bool wallLimited = false;
  bool finishedEarly = false;
  double lastDoneCheck = -1e9;
  double lastProgress = -1e9;
  json progress = json::array();
  const auto simStart = Clock::now();
  std::thread poster([this] { postLoop(); });
  while (true) {
    std::this_thread::sleep_for(std::chrono::milliseconds(250));
    if (gSignal != 0) {
      say("interrupted; stopping the fleet");
      code = 130;
      break;
    }
    bool simEnded = false;
    for (const auto& [name, status] : sup.reapUnexpected()) {
      if (name == "fleet-sim") {
        simEnded = true;
        if (status != 0) {
          say("the simulator exited with status " + std::to_string(status) + "; see " + log(name));
          code = 1;
        }
      } else {
        say(name + " exited unexpectedly with status " + std::to_string(status) + "; see " + log(name));
        code = 1;
      }
    }
    if (simEnded || code != 0) {
      break;
    }
    if (o.untilDone && untilDoneTarget > 0 && generated >= untilDoneTarget && wall() - lastDoneCheck >= 1.0 &&
        [this] {
          std::lock_guard<std::mutex> lock(mu);
          return pending.empty();
        }()) {
      lastDoneCheck = wall();
      if (finishedTasks() >= static_cast<std::size_t>(untilDoneTarget)) {
        say("every task finished at " + std::to_string(static_cast<int>(simS)) + " s simulated; stopping");
        finishedEarly = true;
        sup.signal("fleet-sim", SIGINT);
        sup.waitExit("fleet-sim", 20.0);
        break;
      }
    }
    if (wall() > o.wallLimitS) {
      say("wall-time limit reached; stopping the simulator");
      wallLimited = true;
      sup.signal("fleet-sim", SIGINT);
      sup.waitExit("fleet-sim", 20.0);
      break;
    }
    pollSimTime();
    applyFaults();
    if (simS > 0) {  // tasks arrive on the simulated clock, once it runs
      generateDue();
    }
    if (wall() - lastProgress >= o.progressEveryS) {
      lastProgress = wall();
      say(progressLine(wall()));
      std::lock_guard<std::mutex> lock(mu);
      progress.push_back({{"wall_s", wall()}, {"sim_s", simS}, {"acknowledged", ledger.count()}});
    }
  }
  const double wallS = std::chrono::duration<double>(Clock::now() - simStart).count();
  stopPosting = true;
  poster.join();
  // Faults still in progress end now, so the manager's final state is on disk and nothing is stopped.
  for (std::size_t i = 0; i < faults.size(); ++i) {
    if (faultStarted[i] && !faultEnded[i]) {
      const std::string& who = faultTarget[i];
      if (faults[i].kind == Fault::Kind::StallRobot) {
        sup.signal(who, SIGCONT);
        logFault("SIGCONT " + who + " (end of run)");
      } else if (!who.empty() &&
                 (faults[i].kind == Fault::Kind::KillManager || faults[i].kind == Fault::Kind::KillTraffic)) {
        sup.restart(who);
        logFault("restarted " + who + " (end of run)");
        std::this_thread::sleep_for(std::chrono::seconds(1));
      }
      faultEnded[i] = true;
    }
  }
  if (code == 0) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1500));  // last events and metrics file
    if (auto m = readJson(out / "manager_metrics.json")) {
      writeFile(out / "manager_metrics_final.json", m->dump(1));
    }
  }
  // The manager first: agents that exit while it runs lose their DDS liveliness, and it would
  // (rightly) requeue every active task as "robot lost" after the run had ended.
  if (standby) {
    standby->stop(sup, 5.0);
  } else {
    sup.stop("fleet_manager", 5.0);
  }
  // --serve keeps the adapter: its view holds the run's final state (robots, tasks, roadmap).
  const bool serving = o.serve && code == 0;
  sup.stopAll(5.0, serving ? "wms_adapter" : "");
  say(serving ? "fleet stopped (but the WMS adapter, for the dashboard)" : "fleet stopped");

  // Reconcile the acknowledged tasks with the manager's database.
  const auto contents = standby ? standby->read() : readSqliteStore(db);
  if (standby) {
    // The run's figures and the report read fleet.db: a copy of the PostgreSQL store.
    if (auto e = copyPostgresToSqlite(standby->url(), db); !e.empty()) {
      say(e);
    }
  }
  const Accounting acc = ledger.reconcile(contents.tasks, contents.transitions);
  json summary = readJson(out / "sim_summary.json").value_or(json::object());
  const double simTime = summary.value("sim_time_s", simS);
  // The robot agents' achieved control rate and cycle times (each process writes its own file).
  json agentMetrics = json::array();
  for (const auto& name : agentNames) {
    if (auto m = readJson(out / (name + "_metrics.json"))) {
      agentMetrics.push_back(*m);
    }
  }
  json report = {
      {"scenario", scenario.value("name", std::string())},
      {"robots", robots.size()},
      {"humans", scenario.value("humans", json::object()).value("count", 0)},
      {"agent_processes", agentNames.size()},
      {"duration_s", o.durationS},
      {"sim_time_s", simTime},
      {"wall_time_s", wallS},
      {"real_time_factor", wallS > 0 ? simTime / wallS : 0.0},
      {"wall_limited", wallLimited},
      {"finished_early", finishedEarly},
      {"interrupted", code == 130},
      {"rate_per_min", ratePerMin()},
      {"tasks",
       {{"source", fromList ? "scenario" : "generated"},
        {"generated", generated},
        {"refused", refused},
        {"never_acknowledged", pending.size()},
        {"post_errors", postErrors}}},
      {"accounting", toJson(acc)},
      {"throughput",
       {{"done_per_sim_hour", simTime > 0 ? static_cast<double>(acc.done) * 3600.0 / simTime : 0.0},
        {"done_per_wall_hour", wallS > 0 ? static_cast<double>(acc.done) * 3600.0 / wallS : 0.0}}},
      {"safety",
       {{"contacts", summary.value("contacts", json::object())},
        {"min_separation_m", summary.value("min_separation_m", json::object())},
        {"near_misses", summary.value("near_misses", json::object())},
        {"lockstep_step_timeouts", summary.value("lockstep_step_timeouts", json())}}},
      {"clock", o.wallClock ? "wall" : "lockstep"},
      {"agents", agentMetrics},
      {"faults", faultLog},
      {"fault_plan", json::array()},
      {"progress", progress},
      {"db_error", contents.error},
      {"store", standby ? standby->reportJson() : json{{"backend", "sqlite"}}}};
  for (const auto& f : faults) {
    report["fault_plan"].push_back(describe(f));
  }
  // On the wall clock the manager stamps with epoch time, the replay with the simulator's own: the
  // robot's pose at an assignment cannot be looked up.
  report["kinematic_bound"] =
      o.wallClock
          ? json{{"error", "not in wall-clock runs (the manager's stamps are not the replay's clock)"}}
          : runBounds(out);
  // As for the bound: on the wall clock the manager's stamps are epoch time, not the run's.
  report["saturated"] =
      o.wallClock ? json{{"found", false},
                         {"why", "not in wall-clock runs (the manager's stamps are not the run's clock)"},
                         {"robots", robots.size()},
                         {"peak_waiting", 0}}
                  : saturatedJson(saturatedWindow(contents.transitions, robots.size(), simTime));
  addRunFigures(report, out, o.wallClock);
  if (auto tm = readJson(out / "traffic_manager_summary.json")) {
    report["traffic_manager"] = trafficSummaryJson(*tm, vdaRobots);
  }
  writeFile(out / "loadtest.json", report.dump(2));
  char line[256];
  std::snprintf(
      line, sizeof line,
      "%zu acknowledged: %zu done, %zu failed, %zu cancelled, %zu still tracked; LOST %zu, DUPLICATED %zu",
      acc.acknowledged, acc.done, acc.failed, acc.cancelled, acc.active, acc.lost.size(),
      acc.duplicated.size());
  say(line);
  std::snprintf(
      line, sizeof line,
      "%.0f s simulated in %.0f s wall (%.2fx); end-to-end p50 %.1f s p99 %.1f s; assignment p99 %.2f s",
      simTime, wallS, wallS > 0 ? simTime / wallS : 0.0, acc.endToEndS.p50, acc.endToEndS.p99,
      acc.assignS.p99);
  say(line);
  for (const auto& m : agentMetrics) {
    std::snprintf(line, sizeof line,
                  "%s (%s): %d robots, %.2f cycles/s (configured %.1f Hz), %d overruns, cycle p50 %.2f ms "
                  "p99 %.2f ms max %.1f ms",
                  m.value("id", std::string("?")).c_str(), m.value("clock", std::string("?")).c_str(),
                  m.value("robots", 0), m.value("achieved_hz", 0.0), m.value("configured_hz", 0.0),
                  m.value("overruns", 0), m["cycle_ms"].value("p50", 0.0), m["cycle_ms"].value("p99", 0.0),
                  m["cycle_ms"].value("max", 0.0));
    say(line);
    if (m.contains("conduct")) {
      const auto& c = m["conduct"];
      std::snprintf(line, sizeof line, "%s conduct: %d local-planner recoveries, %d rejoins of a node",
                    m.value("id", std::string("?")).c_str(), c.value("planner_recoveries", 0),
                    c.value("rejoins", 0));
      say(line);
    }
  }
  if (standby) {
    say(standby->summaryLine());
  }
  say(boundLine(report["kinematic_bound"]));
  say(saturatedLine(report["saturated"]));
  for (const auto& l : runFigureLines(report)) {
    say(l);
  }
  if (report.contains("traffic_manager")) {
    say(baseEndsLine(report["traffic_manager"]));
  }
  if (!contents.error.empty()) {
    say("task database: " + contents.error);
    code = code == 0 ? 1 : code;
  }
  if (!o.reportScript.empty() && fs::exists(out / "sim_summary.json")) {
    const std::string cmd =
        "python3 '" + o.reportScript + "' '" + fs::absolute(out).string() + "' >/dev/null";
    if (std::system(cmd.c_str()) == 0) {
      say("report: " + (fs::absolute(out) / "index.html").string());
    } else {
      say("the report script failed: " + cmd);
    }
  }
  if (code == 0 && (!acc.lost.empty() || !acc.duplicated.empty())) {
    code = 3;
  }
  if (serving) {
    serveUntilInterrupted(port);
  }
  return code;
}

void Run::serveUntilInterrupted(int port) {
  // The run folder holds the task database and logs: only the report's own files are served.
  httplib::Server files;
  const std::vector<std::tuple<std::string, fs::path, std::string>> served = {
      {"/", out / "index.html", "text/html; charset=utf-8"},
      {"/index.html", out / "index.html", "text/html; charset=utf-8"},
      {"/viewer.html", out / "viewer.html", "text/html; charset=utf-8"},
      {"/loadtest.json", out / "loadtest.json", "application/json"},
      {"/summary.json", out / "sim_summary.json", "application/json"}};
  for (const auto& [route, path, type] : served) {
    files.Get(route, [path, type](const httplib::Request&, httplib::Response& res) {
      std::ifstream in(path, std::ios::binary);
      if (!in) {
        res.status = 404;
        res.set_content("this run left no " + path.filename().string() + "\n", "text/plain");
        return;
      }
      std::ostringstream body;
      body << in.rdbuf();
      res.set_content(body.str(), type);
    });
  }
  const int filesPort = files.bind_to_any_port("127.0.0.1");
  if (filesPort <= 0) {
    say("cannot serve the report on 127.0.0.1; it is in " + (fs::absolute(out) / "index.html").string());
  }
  std::thread server([&] {
    if (filesPort > 0) {
      files.listen_after_bind();
    }
  });
  say("serving until Ctrl-C: the dashboard on the run's final state at http://127.0.0.1:" +
      std::to_string(port) +
      "/dashboard/ (the fleet is stopped: robots stand where they last reported, actions are refused)" +
      (filesPort > 0 ? "; the report with its replay at http://127.0.0.1:" + std::to_string(filesPort) + "/"
                     : std::string()));
  while (gSignal == 0) {
    std::this_thread::sleep_for(std::chrono::milliseconds(250));
    if (auto gone = sup.reapUnexpected(); !gone.empty()) {
      say("the WMS adapter exited with status " + std::to_string(gone[0].second) + "; see " +
          (out / "wms_adapter.log").string());
      break;
    }
  }
  files.stop();
  server.join();
  sup.stopAll(5.0);
  say("stopped serving");
}

}  // namespace

int runLoadtest(const LoadtestOptions& o) {
  Run r(o);
  return r.run();
}

}  // namespace fleet::ctl
