#include "loadtest_report.hpp"

#include <cstdio>
#include <fstream>
#include <optional>

#include "base_ends.hpp"
#include "run_bounds.hpp"
#include "run_figures.hpp"
#include "run_files.hpp"
#include "saturation.hpp"

namespace fleet::ctl {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

}  // namespace

json buildReport(const LoadtestOptions& o, const fs::path& out, const RunOutcome& run, const Accounting& acc,
                 const StoreContents& contents) {
  json summary = readJsonFile(out / "sim_summary.json").value_or(json::object());
  const double simTime = summary.value("sim_time_s", run.simS);
  const double wallS = run.wallS;
  // The robot agents' achieved control rate and cycle times (each process writes its own file).
  json agentMetrics = json::array();
  for (const auto& name : run.agentNames) {
    if (auto m = readJsonFile(out / (name + "_metrics.json"))) {
      agentMetrics.push_back(*m);
    }
  }
  json report = {
      {"scenario", run.scenario},
      {"robots", run.robots},
      {"humans", run.humans},
      {"agent_processes", run.agentNames.size()},
      {"duration_s", o.durationS},
      {"sim_time_s", simTime},
      {"wall_time_s", wallS},
      {"real_time_factor", wallS > 0 ? simTime / wallS : 0.0},
      {"wall_limited", run.wallLimited},
      {"finished_early", run.finishedEarly},
      {"interrupted", run.interrupted},
      {"rate_per_min", run.ratePerMin},
      {"tasks",
       {{"source", run.fromList ? "scenario" : "generated"},
        {"generated", run.generated},
        {"refused", run.refused},
        {"never_acknowledged", run.neverAcknowledged},
        {"post_errors", run.postErrors}}},
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
      {"faults", run.faultLog},
      {"fault_plan", run.faultPlan},
      {"progress", run.progress},
      {"db_error", contents.error},
      {"store", run.store}};
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
                         {"robots", run.robots},
                         {"peak_waiting", 0}}
                  : saturatedJson(saturatedWindow(contents.transitions, run.robots, simTime));
  addRunFigures(report, out, o.wallClock);
  if (auto tm = readJsonFile(out / "traffic_manager_summary.json")) {
    report["traffic_manager"] = trafficSummaryJson(*tm, run.vdaRobots);
  }
  return report;
}

std::vector<std::string> reportLines(const json& report, const Accounting& acc,
                                     const std::string& storeLine) {
  std::vector<std::string> lines;
  char line[256];
  std::snprintf(
      line, sizeof line,
      "%zu acknowledged: %zu done, %zu failed, %zu cancelled, %zu still tracked; LOST %zu, DUPLICATED %zu",
      acc.acknowledged, acc.done, acc.failed, acc.cancelled, acc.active, acc.lost.size(),
      acc.duplicated.size());
  lines.emplace_back(line);
  const double simTime = report.value("sim_time_s", 0.0);
  const double wallS = report.value("wall_time_s", 0.0);
  std::snprintf(
      line, sizeof line,
      "%.0f s simulated in %.0f s wall (%.2fx); end-to-end p50 %.1f s p99 %.1f s; assignment p99 %.2f s",
      simTime, wallS, wallS > 0 ? simTime / wallS : 0.0, acc.endToEndS.p50, acc.endToEndS.p99,
      acc.assignS.p99);
  lines.emplace_back(line);
  for (const auto& m : report.value("agents", json::array())) {
    const json cycle = m.value("cycle_ms", json::object());
    std::snprintf(line, sizeof line,
                  "%s (%s): %d robots, %.2f cycles/s (configured %.1f Hz), %d overruns, cycle p50 %.2f ms "
                  "p99 %.2f ms max %.1f ms",
                  m.value("id", std::string("?")).c_str(), m.value("clock", std::string("?")).c_str(),
                  m.value("robots", 0), m.value("achieved_hz", 0.0), m.value("configured_hz", 0.0),
                  m.value("overruns", 0), cycle.value("p50", 0.0), cycle.value("p99", 0.0),
                  cycle.value("max", 0.0));
    lines.emplace_back(line);
    if (m.contains("conduct")) {
      const auto& c = m["conduct"];
      std::snprintf(line, sizeof line, "%s conduct: %d local-planner recoveries, %d rejoins of a node",
                    m.value("id", std::string("?")).c_str(), c.value("planner_recoveries", 0),
                    c.value("rejoins", 0));
      lines.emplace_back(line);
    }
  }
  if (!storeLine.empty()) {
    lines.push_back(storeLine);
  }
  lines.push_back(boundLine(report["kinematic_bound"]));
  lines.push_back(saturatedLine(report["saturated"]));
  for (const auto& l : runFigureLines(report)) {
    lines.push_back(l);
  }
  if (report.contains("traffic_manager")) {
    lines.push_back(baseEndsLine(report["traffic_manager"]));
  }
  if (const std::string err = report.value("db_error", std::string()); !err.empty()) {
    lines.push_back("task database: " + err);
  }
  return lines;
}

}  // namespace fleet::ctl
