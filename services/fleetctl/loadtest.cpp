#include "loadtest.hpp"

#include <httplib.h>
#include <signal.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <sstream>
#include <thread>
#include <tuple>

#include "fault_injector.hpp"
#include "fleet_launch.hpp"
#include "loadtest_report.hpp"
#include "loadtest_scenario.hpp"
#include "run_files.hpp"
#include "standby_managers.hpp"
#include "store_contents.hpp"
#include "supervisor.hpp"
#include "task_feeder.hpp"

// The load test's driver: its stages in order (the scenario, the fleet, the tasks, the faults,
// the report; each in a file of its own with its own tests), the run's progress and its end.

namespace fleet::ctl {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using Clock = std::chrono::steady_clock;

std::atomic<int> gSignal{0};
extern "C" void onLoadtestSignal(int sig) {
  gSignal = sig;
}

void say(const std::string& s) {
  std::cout << "loadtest: " << s << std::endl;
}

int refuse(const Error& e) {
  std::cerr << "fleetctl loadtest: " << e.message << "\n";
  return 2;
}

std::unique_ptr<httplib::Client> adapterClient(int port) {
  auto c = std::make_unique<httplib::Client>("127.0.0.1", port);
  c->set_connection_timeout(2, 0);
  c->set_read_timeout(10, 0);
  // The adapter started here inherits FLEET_WMS_TOKEN from this environment and then asks for it
  // on every request; without it the run stalled at "0.0 s sim" on 401s.
  if (const char* token = std::getenv("FLEET_WMS_TOKEN"); token != nullptr && *token != '\0') {
    c->set_bearer_token_auth(token);
  }
  return c;
}

/// Faults act on the run's processes through its supervisor, and on areas through the WMS API.
class SupervisedFaults : public FaultActions {
 public:
  SupervisedFaults(Supervisor& sup, StandbyManagers* standby, httplib::Client& http)
      : sup_(sup), standby_(standby), http_(http) {}
  void signal(const std::string& process, int sig) override { sup_.signal(process, sig); }
  void kill(const std::string& process) override { sup_.killHard(process); }
  void restart(const std::string& process) override { sup_.restart(process); }
  std::string killActiveManager() override { return standby_ ? standby_->killActive(sup_) : std::string(); }
  std::string putClosure(const std::string& path, const json& body) override {
    auto r = http_.Put(path, body.dump(), "application/json");
    return r ? std::to_string(r->status) + " " + r->body : std::string("adapter unreachable");
  }
  std::string deleteClosure(const std::string& path) override {
    auto r = http_.Delete(path);
    return r ? std::to_string(r->status) : std::string("adapter unreachable");
  }

 private:
  Supervisor& sup_;
  StandbyManagers* standby_;
  httplib::Client& http_;
};

struct Run {
  LoadtestOptions o;  // a copy
  fs::path out;
  Supervisor sup;
  std::unique_ptr<StandbyManagers> standby;   // --store postgresql: the database and two managers
  std::unique_ptr<httplib::Client> http;      // progress, sim time and faults (main thread)
  std::unique_ptr<httplib::Client> postHttp;  // task submission (poster thread)
  double simS = 0;
  double firstStampS = 0;  // wall clock: the first robot stamp seen

  explicit Run(const LoadtestOptions& opt) : o(opt), out(opt.out) {}

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

  /// The adapter's count of tasks in each state ({} when it does not answer).
  json tasksByState() {
    if (auto r = http->Get("/v1/metrics"); r && r->status == 200) {
      auto m = json::parse(r->body, nullptr, false);
      if (m.is_object() && m.contains("tasks_by_state") && m["tasks_by_state"].is_object()) {
        return m["tasks_by_state"];
      }
    }
    return json::object();
  }

  /// Tasks the manager holds in a final state (done, failed, cancelled).
  std::size_t finishedTasks() {
    std::size_t n = 0;
    const json states = tasksByState();
    for (const char* k : {"done", "failed", "cancelled"}) {
      if (states.contains(k) && states[k].is_number_unsigned()) {
        n += states[k].get<std::size_t>();
      }
    }
    return n;
  }

  std::string progressLine(double wallS, const TaskFeeder& feeder) {
    std::string states;
    const json byState = tasksByState();
    for (const auto& [k, v] : byState.items()) {
      states += " " + k + "=" + v.dump();
    }
    char buf[160];
    std::snprintf(buf, sizeof buf, "%5.0f s wall | %6.1f s sim (%.2fx) | acknowledged %zu pending %zu |",
                  wallS, simS, wallS > 0 ? simS / wallS : 0.0, feeder.acknowledged(), feeder.pending());
    return buf + states;
  }

  /// Waits up to 30 s for the adapter to report a healthy manager; 0, or the exit code.
  int waitHealthy(const FleetPlan& plan) {
    const auto t0 = Clock::now();
    while (std::chrono::duration<double>(Clock::now() - t0).count() < 30 && gSignal == 0) {
      if (auto r = http->Get("/v1/health"); r && r->status == 200) {
        return 0;
      }
      if (auto gone = sup.reapUnexpected(); !gone.empty()) {
        say(gone[0].first + " exited with status " + std::to_string(gone[0].second) + " at start; see " +
            plan.logOf(gone[0].first));
        return 1;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    say(gSignal ? "interrupted" : "the WMS adapter did not report a healthy fleet manager within 30 s");
    return gSignal ? 130 : 1;
  }

  void announce(const RunScenario& run, const FleetPlan& plan, const std::vector<Fault>& faults,
                int listTarget) {
    const auto& sc = run.scenario;
    say("scenario " + sc.value("name", std::string("?")) + ": " + std::to_string(run.robots.size()) +
        " robots, " + std::to_string(sc.value("humans", json::object()).value("count", 0)) + " humans, " +
        std::to_string(static_cast<int>(o.durationS)) + " s simulated (wall limit " +
        std::to_string(static_cast<int>(o.wallLimitS)) + " s), " + std::to_string(plan.agentNames.size()) +
        " agent process(es), DDS domain " + std::to_string(plan.domain) +
        ", WMS API http://127.0.0.1:" + std::to_string(plan.port) + ", run folder " + out.string());
    if (run.fromList) {
      std::string note;
      if (listTarget < static_cast<int>(run.listTasks.size())) {
        note = " (" + std::to_string(run.listTasks.size() - static_cast<std::size_t>(listTarget)) +
               " at or after the end (" + std::to_string(static_cast<int>(o.durationS)) +
               " s) are not posted)";
      }
      say("tasks: " + std::to_string(run.listTasks.size()) + " from the scenario's task list" + note);
    } else {
      char rate[64];
      std::snprintf(rate, sizeof rate, "%g", taskRatePerMin(o, run, listTarget));
      say(std::string("tasks: generated at ") + rate + " per minute" +
          (o.maxTasks > 0 ? ", at most " + std::to_string(o.maxTasks) : std::string()) +
          (sc.contains("tasks") ? " (the scenario's task list of " + std::to_string(run.listTasks.size()) +
                                      " is not used: --rate, --tasks or --generate-tasks)"
                                : std::string()));
    }
    for (const auto& f : faults) {
      say("fault planned: " + describe(f));
    }
    for (const auto& w : plan.warnings) {
      say(w);
    }
  }

  int run();
  /// --serve: the adapter (kept running, on `port`) and the report's files on loopback until Ctrl-C.
  void serveUntilInterrupted(int port);
};

int Run::run() {
  std::error_code ec;
  fs::create_directories(out, ec);
  if (ec) {
    say("cannot create " + out.string() + ": " + ec.message());
    return 1;
  }
  auto faults = parseFaults(o.faults);
  if (!faults) {
    return refuse(faults.error());
  }
  auto scenario = prepareScenario(o, out);
  if (!scenario) {
    return refuse(scenario.error());
  }
  const RunScenario& rs = *scenario;
  if (auto ok = checkFaults(*faults, rs, o.agents); !ok) {
    return refuse(ok.error());
  }
  if (auto ok = checkDdsSecurity(o, dropFraction(*faults)); !ok) {
    return refuse(ok.error());
  }
  if (o.store == "postgresql") {
    standby = std::make_unique<StandbyManagers>(out, o.binDir);
    if (!standby->ok()) {
      say("cannot start PostgreSQL for --store postgresql: " + standby->error());
      return 1;
    }
    say("store: PostgreSQL of the run's own at " + standby->url() + ", two fleet managers on it");
  }
  auto planned = planFleet(o, rs, *faults, out, standby.get());
  if (!planned) {
    return refuse(planned.error());
  }
  const FleetPlan& plan = *planned;
  const int listTarget =
      rs.fromList
          ? static_cast<int>(std::count_if(rs.listTasks.begin(), rs.listTasks.end(),
                                           [&](const ScenarioTask& t) { return t.atS < o.durationS; }))
          : o.maxTasks;  // --until-done: stop once this many tasks are finished

  struct sigaction sa {};
  sa.sa_handler = onLoadtestSignal;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
  sigaction(SIGHUP, &sa, nullptr);

  announce(rs, plan, *faults, listTarget);
  if (auto ok = makeIdentities(o, plan); !ok) {
    say(ok.error().message);
    return 2;
  }
  for (const auto& s : plan.specs) {
    if (!sup.start(s)) {
      say("cannot start " + s.name);
      return 1;
    }
  }
  http = adapterClient(plan.port);
  postHttp = adapterClient(plan.port);
  if (int code = waitHealthy(plan); code != 0) {
    return code;
  }
  say("live dashboard: http://127.0.0.1:" + std::to_string(plan.port) + "/dashboard/ (open it in a browser)");
  sup.start(plan.sim);

  TaskFeeder feeder({rs.listTasks, rs.fromList, rs.pickups, rs.dropoffs, taskRatePerMin(o, rs, listTarget),
                     o.maxTasks, o.durationS, o.seed},
                    say);
  SupervisedFaults actions(sup, standby.get(), *http);
  FaultInjector injector(*faults, plan.agentOfRobot, standby != nullptr, actions, say);
  int code = 0;
  bool wallLimited = false;
  bool finishedEarly = false;
  double lastDoneCheck = -1e9;
  double lastProgress = -1e9;
  json progress = json::array();
  const auto simStart = Clock::now();
  auto wall = [&] { return std::chrono::duration<double>(Clock::now() - simStart).count(); };
  std::atomic<bool> stopPosting{false};
  std::thread poster([&] { feeder.run(*postHttp, stopPosting); });
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
          say("the simulator exited with status " + std::to_string(status) + "; see " + plan.logOf(name));
          code = 1;
        }
      } else {
        say(name + " exited unexpectedly with status " + std::to_string(status) + "; see " +
            plan.logOf(name));
        code = 1;
      }
    }
    if (simEnded || code != 0) {
      break;
    }
    if (o.untilDone && listTarget > 0 && feeder.generated() >= listTarget && wall() - lastDoneCheck >= 1.0 &&
        feeder.pending() == 0) {
      lastDoneCheck = wall();
      if (finishedTasks() >= static_cast<std::size_t>(listTarget)) {
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
    injector.apply(simS, Clock::now());
    if (simS > 0) {  // tasks arrive on the simulated clock, once it runs
      feeder.due(simS);
    }
    if (wall() - lastProgress >= o.progressEveryS) {
      lastProgress = wall();
      say(progressLine(wall(), feeder));
      progress.push_back({{"wall_s", wall()}, {"sim_s", simS}, {"acknowledged", feeder.acknowledged()}});
    }
  }
  const double wallS = wall();
  stopPosting = true;
  poster.join();
  // Faults still in progress end now, so the manager's final state is on disk and nothing is stopped.
  if (injector.endAll(simS) > 0) {
    std::this_thread::sleep_for(std::chrono::seconds(1));
  }
  if (code == 0) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1500));  // last events and metrics file
    if (auto m = readJsonFile(out / "manager_metrics.json")) {
      writeTextFile(out / "manager_metrics_final.json", m->dump(1));
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
  const auto contents = standby ? standby->read() : readSqliteStore(plan.db);
  if (standby) {
    // The run's figures and the report read fleet.db: a copy of the PostgreSQL store.
    if (auto e = copyPostgresToSqlite(standby->url(), plan.db); !e.empty()) {
      say(e);
    }
  }
  const Accounting acc = feeder.reconcile(contents.tasks, contents.transitions);
  RunOutcome outcome;
  outcome.scenario = rs.scenario.value("name", std::string());
  outcome.robots = rs.robots.size();
  outcome.humans = rs.scenario.value("humans", json::object()).value("count", 0);
  outcome.agentNames = plan.agentNames;
  outcome.vdaRobots = plan.vdaRobots;
  outcome.simS = simS;
  outcome.wallS = wallS;
  outcome.wallLimited = wallLimited;
  outcome.finishedEarly = finishedEarly;
  outcome.interrupted = code == 130;
  outcome.ratePerMin = taskRatePerMin(o, rs, listTarget);
  outcome.fromList = rs.fromList;
  outcome.generated = feeder.generated();
  outcome.refused = feeder.refused();
  outcome.postErrors = feeder.postErrors();
  outcome.neverAcknowledged = feeder.pending();
  for (const auto& f : *faults) {
    outcome.faultPlan.push_back(describe(f));
  }
  outcome.faultLog = injector.log();
  outcome.progress = progress;
  if (standby) {
    outcome.store = standby->reportJson();
  }
  const json report = buildReport(o, out, outcome, acc, contents);
  writeTextFile(out / "loadtest.json", report.dump(2));
  for (const auto& line : reportLines(report, acc, standby ? standby->summaryLine() : std::string())) {
    say(line);
  }
  if (!contents.error.empty()) {
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
    serveUntilInterrupted(plan.port);
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
