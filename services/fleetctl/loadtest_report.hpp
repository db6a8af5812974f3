#pragma once

// The load test's last stage: what a run leaves. From the run folder's files (the simulator's
// summary, the agents' metrics, the traffic manager's summary, the replay and the task store's
// copy), the task ledger's accounting and how the run went, it builds loadtest.json's report and
// the summary lines printed at the end.

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "loadtest.hpp"
#include "store_contents.hpp"
#include "task_ledger.hpp"

namespace fleet::ctl {

/// How the run went, as the driver saw it.
struct RunOutcome {
  std::string scenario;  // its name
  std::size_t robots = 0;
  int humans = 0;
  std::vector<std::string> agentNames;  // agent processes (their metrics files)
  std::set<std::string> vdaRobots;
  double simS = 0;   // the last simulated time seen (when the simulator left no summary)
  double wallS = 0;  // wall time from the simulator's start
  bool wallLimited = false, finishedEarly = false, interrupted = false;
  double ratePerMin = 0;
  bool fromList = false;
  int generated = 0, refused = 0, postErrors = 0;
  std::size_t neverAcknowledged = 0;
  std::vector<std::string> faultPlan;  // described
  nlohmann::json faultLog = nlohmann::json::array();
  nlohmann::json progress = nlohmann::json::array();
  nlohmann::json store = {{"backend", "sqlite"}};
};

/// loadtest.json's content. Reads the run folder; the kinematic bound and the saturated window
/// only on the simulated clock (on the wall clock the manager's stamps are epoch time).
nlohmann::json buildReport(const LoadtestOptions& o, const std::filesystem::path& out, const RunOutcome& run,
                           const Accounting& acc, const StoreContents& contents);

/// The lines printed at the end: accounting, timing, each agent process, the store (`storeLine`,
/// when not empty), the bound, the saturated window, the fleet figures and the base ends.
std::vector<std::string> reportLines(const nlohmann::json& report, const Accounting& acc,
                                     const std::string& storeLine);

}  // namespace fleet::ctl
