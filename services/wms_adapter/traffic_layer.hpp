#pragma once

// The dashboard's traffic layer (docs/operator-guide.md#dashboard): the traffic manager's roadmap,
// each robot's release (base: what it may drive; horizon: what is planned after it) and the station
// queues with the robots waiting in them, as the page draws them. Pure functions over the messages,
// so the JSON is tested without DDS or a server.

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "fleet/messages/messages.hpp"

namespace fleet::wms {

/// The node kinds of Roadmap.kinds (idl/fleet.idl).
enum class RoadmapKind : std::uint8_t {
  Lane = 0,
  Station = 1,
  Approach = 2,
  Queue = 3,
  Parking = 4,
  Charger = 5,
  Exit = 6
};

/// The line robots wait in before a station, read off the roadmap's shape: the queue nodes whose
/// one-way chain ends at the station's approach node (or its dock).
struct StationQueue {
  std::string station;              // the site's station at the dock, else "node <dock>"
  std::int32_t dock = -1;           // the station's node
  std::vector<std::int32_t> nodes;  // queue nodes, the head (next in) first
};

/// Every station with a queue. `stations` is the site picture's "stations" array (name, x, y); a
/// dock is named by the station within 0.25 m of it.
std::vector<StationQueue> stationQueues(const msg::Roadmap& m, const nlohmann::json& stations);

/// The roadmap for the page, null when too large to draw (over kMaxDrawnNodes nodes or
/// kMaxDrawnEdges lanes): node positions flat ([x0, y0, x1, y1, ...], to the centimetre), their
/// kinds, closed nodes, lanes both ways ([a, b, ...], each pair once), one-way lanes ([from, to,
/// ...]), closed lanes, and the station queues.
nlohmann::json roadmapJson(const msg::Roadmap& m, const std::vector<StationQueue>& queues);
inline constexpr std::size_t kMaxDrawnNodes = 250'000;
inline constexpr std::size_t kMaxDrawnEdges = 1'000'000;

/// One robot's release: node ids and positions (flat, centimetres) of its base and horizon.
nlohmann::json releaseJson(const msg::TrafficRelease& r);

/// Who is in each queue now: for every queue, the robots standing on its nodes (within
/// kQueueTolerance), head first, and the robot at the station's dock.
nlohmann::json queuesJson(const std::vector<StationQueue>& queues, const msg::Roadmap& m,
                          const std::vector<msg::RobotState>& robots);
/// m from a node's position within which a robot counts as standing on it (a waiting robot stops
/// on the node give or take its tracking error; a robot driving past is on it only briefly).
inline constexpr double kQueueTolerance = 0.3;

}  // namespace fleet::wms
