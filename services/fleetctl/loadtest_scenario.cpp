#include "loadtest_scenario.hpp"

#include <algorithm>
#include <fstream>
#include <iostream>
#include <optional>

#include "fleet/core/config.hpp"
#include "fleet/fleet/site_stations.hpp"
#include "run_files.hpp"
#include "scenario_gen.hpp"
#include "site_lines.hpp"

namespace fleet::ctl {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

/// A scenario file as is: its site resolved and its task list checked.
Expected<void> fromFile(const LoadtestOptions& o, RunScenario& run) {
  auto s = readJsonFile(o.scenario);
  if (!s) {
    return unexpected("scenario", o.scenario + ": cannot read a JSON scenario");
  }
  run.scenario = *s;
  run.scenario["duration_s"] = o.durationS;
  try {
    run.scenario = resolveScenarioSite(std::move(run.scenario), o.scenario);
    if (auto list = parseScenarioTasks(run.scenario, o.scenario)) {
      run.listTasks = std::move(*list);
      run.fromList = !o.generateTasks;
    }
  } catch (const ConfigError& e) {
    return unexpected("scenario", e.what());
  }
  std::stable_sort(run.listTasks.begin(), run.listTasks.end(),
                   [](const ScenarioTask& a, const ScenarioTask& b) { return a.atS < b.atS; });
  // A relative map file stays relative to the original scenario's folder.
  auto& sc = run.scenario;
  if (sc.contains("map") && sc["map"].is_object() && sc["map"].contains("file")) {
    sc["map"]["file"] =
        (fs::absolute(o.scenario).parent_path() / sc["map"]["file"].get<std::string>()).string();
  }
  return {};
}

/// A scenario generated for the fleet size: its map and stations become the run's site, so every
/// service reads a site as in production; the template gives the rest, and its site the robot.
Expected<void> generated(const LoadtestOptions& o, const fs::path& out, RunScenario& run) {
  auto t = readJsonFile(o.templ);
  if (!t) {
    return unexpected("scenario", o.templ + ": cannot read the scenario template");
  }
  if (t->contains("site")) {
    try {
      *t = inlineSiteRobot(*t, o.templ);
    } catch (const ConfigError& e) {
      return unexpected("scenario", e.what());
    }
  }
  auto g = generateScenario(*t, {o.robots, o.humans, o.durationS, o.seed, o.siteRobots});
  if (!g) {
    return unexpected(g.error());
  }
  auto [site, rest] = splitSite(*g);
  writeTextFile(out / "site.json", site.dump(1));
  // The site says where robots enter, wait at and leave each station, as a shipped site does. A
  // generated site whose roadmap has errors (none of the sizes tried since the pickups are spaced
  // for their lines: docs/algorithms.md, "Generated sites' pickups spaced for their lines") still
  // runs, its lines left to the roadmap, and says why.
  if (auto lines = spellOutLinesInPlace((out / "site.json").string()); !lines) {
    std::cerr << "loadtest: warning: the generated site's station lines are not written into it:\n"
              << lines.error().message << "\n";
  }
  rest["site"] = fs::absolute(out / "site.json").string();
  run.scenario = resolveScenarioSite(rest, (out / "scenario.json").string());
  return {};
}

}  // namespace

Expected<RunScenario> prepareScenario(const LoadtestOptions& o, const fs::path& out) {
  RunScenario run;
  run.file = out / "scenario.json";
  if (auto made = o.scenario.empty() ? generated(o, out, run) : fromFile(o, run); !made) {
    return unexpected(made.error());
  }
  json& scenario = run.scenario;
  {
    json forRun = scenario;
    forRun.erase("site_stations");  // fleetctl's own copy of the site's stations
    writeTextFile(run.file, forRun.dump(1));
  }
  for (const auto& s : scenarioStations(scenario)) {
    if (s.value("kind", "") == "pickup") {
      run.pickups.push_back(s["name"]);
    } else if (s.value("kind", "") == "dropoff") {
      run.dropoffs.push_back(s["name"]);
    }
  }
  if (run.pickups.empty() || run.dropoffs.empty()) {
    return unexpected("scenario", "the scenario has no pickup or no dropoff station");
  }
  for (const auto& r : scenario.value("robots", json::array())) {
    run.robots.push_back(r.value("id", ""));
  }
  if (!scenario.contains("site") || !scenario["site"].is_string()) {
    // Every robot drives what the traffic manager releases, on the roadmap it builds from the site.
    return unexpected("scenario",
                      "the scenario names no site (\"site\"): the traffic manager needs one for its roadmap");
  }
  run.siteFile = scenario["site"].get<std::string>();
  auto site = fleet::loadSiteFile(run.siteFile);
  if (!site) {
    return unexpected(site.error());
  }
  run.widthM = site->map.width() * site->map.resolution();
  run.heightM = site->map.height() * site->map.resolution();
  if (run.widthM <= 0) {
    run.widthM = 100;
    run.heightM = 50;
  }
  return run;
}

Expected<void> checkFaults(const std::vector<Fault>& faults, const RunScenario& run, int agents) {
  for (const auto& f : faults) {
    if (f.kind == Fault::Kind::StallRobot &&
        std::find(run.robots.begin(), run.robots.end(), f.robot) == run.robots.end()) {
      return unexpected("fault",
                        "--fault stall:" + f.robot + ": the scenario has no robot '" + f.robot + "'");
    }
    if (f.kind == Fault::Kind::KillAgent && f.agent >= agents) {
      return unexpected("fault", "--fault " + describe(f) + ": there are only " + std::to_string(agents) +
                                     " agent process(es) (--agents)");
    }
  }
  return {};
}

double taskRatePerMin(const LoadtestOptions& o, const RunScenario& run, int listTarget) {
  if (run.fromList) {
    return o.durationS > 0 ? static_cast<double>(listTarget) * 60.0 / o.durationS : 0.0;
  }
  return o.ratePerMin > 0 ? o.ratePerMin : 0.75 * static_cast<double>(run.robots.size());
}

}  // namespace fleet::ctl
