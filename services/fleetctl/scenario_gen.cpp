#include "scenario_gen.hpp"

#include <algorithm>
#include <cmath>
#include <string>

namespace fleet::ctl {
namespace {

constexpr double kRes = 0.5;            // m per cell, as in the template
constexpr double kAreaPerRobot = 30.0;  // m², the small warehouse's floor per robot
constexpr double kParkDx = 1.2;         // m between parked robots
// Parking, a well-formed site (a parked robot is in nobody's way: the roadmap's lattice keeps clear
// of parked robots, RoadmapOptions::parkingClear). Rows face north, the first 0.9 m off the wall
// like the small warehouse's, each with a lane 0.85 m above it; a row's ends 2.5 m from the side
// walls so the lanes join round them. A fleet that fits in one row parks in one; several rows are
// kRowDy apart and made of blocks of kBlock places with a lane's gap between blocks, so every lane
// between rows is joined to the others every ~11 m. Rows 2 m apart without the gaps made each lane
// a 60 m dead end and the site for 100 stood (virtual fleet, seeds 1-4: 2-12 tasks in 600 s; with
// the gaps 65-70; the earlier rows 1.6 m apart with lanes beside the parked robots 17-35).
constexpr double kRowY = 0.9;
constexpr double kRowEnd = 2.5;
constexpr double kRowDy = 2.0;
constexpr int kBlock = 8;
constexpr double kStationGap = 2.5;  // m between drop-offs / chargers
// Pickups dock along the top wall, entered along the row and left towards the next one, so each
// takes its line (three places a following distance apart, 3 m), its exit (1 m) and a following
// distance to the next one's line (1 m) beside its dock (0.5 m). Closer, the next one's line
// shuts its way out when full: the roadmap refuses that (the sites for 30, 60 and 70 robots) or
// leaves no room for a line at all (24 of the 25 pickups of the site for 100: one robot admitted
// a pickup).
constexpr double kPickupGap = 5.5;

nlohmann::json station(const std::string& name, const char* kind, double x, double y, double theta) {
  return {{"name", name}, {"kind", kind}, {"pose", {x, y, theta}}};
}

}  // namespace

Expected<nlohmann::json> generateScenario(const nlohmann::json& templ, const ScenarioSize& size) {
  if (size.robots < 1 || size.robots > 2000) {
    return unexpected("invalid", "--robots: expected 1..2000, got " + std::to_string(size.robots));
  }
  if (size.humans < 0 || size.humans > 5000) {
    return unexpected("invalid", "--humans: expected 0..5000, got " + std::to_string(size.humans));
  }
  if (size.siteRobots != 0 && (size.siteRobots < size.robots || size.siteRobots > 2000)) {
    return unexpected("invalid", "--site-for: expected " + std::to_string(size.robots) +
                                     "..2000 (at least --robots), got " + std::to_string(size.siteRobots));
  }
  if (!templ.is_object()) {
    return unexpected("invalid", "the scenario template is not a JSON object");
  }
  const int sized = size.siteRobots > 0 ? size.siteRobots : size.robots;
  const double n = sized;
  // Floor area from the fleet size, 3:2 aspect; at least the small warehouse (30 m x 20 m).
  const double area = std::max(600.0, kAreaPerRobot * n);
  double widthM = std::max(30.0, std::round(std::sqrt(area * 1.5)));
  // Parking: rows along the bottom margin; the margin grows with the number of rows.
  const bool oneRow = sized <= static_cast<int>(std::floor((widthM - 2.0 * kRowEnd) / kParkDx)) + 1;
  const auto placeX = [&](int i) { return kRowEnd + i * kParkDx + (oneRow ? 0 : i / kBlock) * kParkDx; };
  int perRow = sized;
  if (!oneRow) {
    perRow = 0;
    while (placeX(perRow) <= widthM - kRowEnd) {
      ++perRow;
    }
  }
  const int rows = (sized + perRow - 1) / perRow;
  // The bottom margin holds the rows, the last one's lane and that lane's clearance (0.85 + 0.4 m).
  const double marginM = std::max(2.5, std::ceil((kRowY + (rows - 1) * kRowDy + 1.25) / kRes) * kRes);
  double heightM = std::max(20.0, std::round(area / widthM) + 2.0 * (marginM - 2.5));
  const int wCells = static_cast<int>(widthM / kRes);
  const int hCells = static_cast<int>(heightM / kRes);
  widthM = wCells * kRes;
  heightM = hCells * kRes;

  nlohmann::json s = templ;
  s.erase("tasks");  // the template's task list names the template's stations
  // The generated map and stations replace the template's site (inlineSiteRobot() keeps its robot).
  s.erase("site");
  s["name"] = "loadtest-" + std::to_string(size.robots) + "r-" + std::to_string(size.humans) + "h" +
              (sized != size.robots ? "-site" + std::to_string(sized) : "");
  s["seed"] = size.seed;
  s["duration_s"] = size.durationS;
  s["map"] = {{"warehouse",
               {{"width", wCells},
                {"height", hCells},
                {"margin", static_cast<int>(marginM / kRes)},
                {"shelf_width", 8},
                {"shelf_height", 2},
                {"aisle_x", 3},
                {"aisle_y", 3}}},
              {"resolution", kRes}};

  nlohmann::json stations = nlohmann::json::array();
  int k = 0;
  for (int r = 0; r < rows; ++r) {
    for (int i = 0; i < perRow && k < sized; ++i) {
      ++k;
      stations.push_back(
          station("PARK-" + std::to_string(k), "parking", placeX(i), kRowY + r * kRowDy, 1.5708));
    }
  }
  // Chargers, pickups, drop-offs: about one per ten, four and five robots, as room allows (pickups
  // at most one per kPickupGap of the top wall).
  const double sideY0 = marginM + 1.0;
  const double sideY1 = heightM - marginM - 1.0;
  const int sideRoom = std::max(1, static_cast<int>((sideY1 - sideY0) / kStationGap) + 1);
  const int topRoom = static_cast<int>((widthM - 7.0) / kPickupGap) + 1;  // spread from 3.5 m in
  const int chargers = std::clamp(sized / 10, 3, sideRoom);
  const int pickups = std::clamp(sized / 4, 5, std::max(5, topRoom));
  const int dropoffs = std::clamp(sized / 5, 4, sideRoom);
  auto spread = [](double lo, double hi, int count, int i) {
    return count == 1 ? (lo + hi) / 2 : lo + (hi - lo) * i / (count - 1);
  };
  for (int i = 0; i < chargers; ++i) {
    stations.push_back(station("CHG-" + std::to_string(i + 1), "charging", 1.5,
                               spread(sideY0, sideY1, chargers, i), 3.1416));
  }
  for (int i = 0; i < pickups; ++i) {
    stations.push_back(station("P-" + std::to_string(i + 1), "pickup", spread(3.5, widthM - 3.5, pickups, i),
                               heightM - 1.5, 1.5708));
  }
  for (int i = 0; i < dropoffs; ++i) {
    stations.push_back(station("D-" + std::to_string(i + 1), "dropoff", widthM - 1.5,
                               spread(sideY0, sideY1, dropoffs, i), 3.1416));
  }
  s["stations"] = stations;

  nlohmann::json robots = nlohmann::json::array();
  for (int i = 1; i <= size.robots; ++i) {
    robots.push_back({{"id", "r" + std::to_string(i)}, {"start_station", "PARK-" + std::to_string(i)}});
  }
  s["robots"] = robots;

  // Landmarks on the walls every ~10 m, for the robots' localisation.
  nlohmann::json landmarks = nlohmann::json::array();
  int id = 1;
  for (double y = 5.0; y < heightM - 2.0; y += 10.0) {
    landmarks.push_back({{"id", id++}, {"position", {0.25, y}}});
    landmarks.push_back({{"id", id++}, {"position", {widthM - 0.25, y}}});
  }
  for (double x = 5.0; x < widthM - 2.0; x += 10.0) {
    landmarks.push_back({{"id", id++}, {"position", {x, heightM - 0.25}}});
  }
  s["landmarks"] = landmarks;

  nlohmann::json humans = templ.contains("humans") ? templ["humans"] : nlohmann::json::object();
  humans["count"] = size.humans;
  // People walk in the top margin (pickups) and the middle of the shelf area.
  humans["spawn_areas"] = {{2.0, heightM - marginM + 0.5, widthM - 2.0, heightM - 1.0}};
  s["humans"] = humans;
  return s;
}

std::pair<double, double> mapExtent(const nlohmann::json& scenario) {
  const auto& m = scenario.value("map", nlohmann::json::object());
  if (!m.contains("warehouse")) {
    return {0.0, 0.0};
  }
  const double r = m.value("resolution", 1.0);
  return {m["warehouse"].value("width", 0) * r, m["warehouse"].value("height", 0) * r};
}

}  // namespace fleet::ctl
