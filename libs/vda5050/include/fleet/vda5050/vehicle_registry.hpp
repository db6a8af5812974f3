#pragma once

// The master control's view of its VDA 5050 vehicles, from what they publish: every message on
// the interface is matched to a configured vehicle by its topic, read, checked (serial number
// and map, nodes it reports against the nodes it was ordered) and turned into a health the fleet
// understands. Bad input never throws: it is refused with a reason, counted, and - when it comes
// from a known vehicle - marks that vehicle faulted until it reports a good state again.

#include <cstdint>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "fleet/vda5050/factsheet.hpp"
#include "fleet/vda5050/order.hpp"
#include "fleet/vda5050/state.hpp"

namespace fleet::vda5050 {

struct VehicleEntry {
  std::string manufacturer;
  std::string serial;
  std::string robot_id;  // the id the rest of the fleet knows it by
};

/// kOnline: in traffic control. The others leave it: the planner treats it as an obstacle and
/// its task is re-queued.
enum class VehicleHealth { kUnknown, kOnline, kManual, kFault, kOffline };
const char* toString(VehicleHealth h);

struct VehicleView {
  VehicleEntry entry;
  VehicleHealth health = VehicleHealth::kUnknown;
  std::string reason;  // why it is not online, for the log and the task's requeue reason
  std::optional<State> state;
  std::optional<Factsheet> factsheet;
  std::set<std::string> ordered_nodes;  // every nodeId sent in its current order
  std::string map_id;
};

/// What the registry refuses at its edge before a message's content counts.
struct RegistryLimits {
  std::size_t maxMessageBytes = 256 * 1024;  // the broker's message_size_limit by default
  /// Where a vehicle can plausibly be (m): the site's extent and a margin. Until the roadmap is
  /// known, a coarse bound of +-1e5 m; a position outside it (or not finite) is refused.
  double minX = -1e5;
  double minY = -1e5;
  double maxX = 1e5;
  double maxY = 1e5;
};

/// Problems with a configured vehicle list, each naming the key ("vehicles[1].serial: ..."):
/// MQTT wildcards ('#', '+') or '/' in a manufacturer or serial (its topics would be others'),
/// empty names, and two vehicles with one identity or one robot id.
std::vector<std::string> vehicleEntryProblems(const std::vector<VehicleEntry>& vehicles);

struct RegistryOutcome {
  bool accepted = false;
  std::string robot_id;  // empty when the message matched no vehicle
  std::string reason;    // why it was refused
  bool health_changed = false;
};

class VehicleRegistry {
 public:
  VehicleRegistry(std::string interface_name, std::string map_id, std::vector<VehicleEntry> vehicles,
                  RegistryLimits limits = {});
  /// The site's extent (from the roadmap) with a margin: where a state's agvPosition may be.
  void setSiteBounds(double minX, double minY, double maxX, double maxY);

  /// One message from the broker.
  RegistryOutcome onMessage(const std::string& topic, const std::string& payload);
  /// Records an order sent to a vehicle: the nodes it may report from now on.
  void ordered(const std::string& robot_id, const Order& order);

  [[nodiscard]] const VehicleView* find(const std::string& robot_id) const;
  [[nodiscard]] const std::map<std::string, VehicleView>& vehicles() const { return vehicles_; }
  /// Refusals by kind: "unknown_serial", "bad_message", "wrong_serial", "other_map",
  /// "node_never_ordered", "unknown_topic", "too_large" (bytes or JSON shape past the limits),
  /// "unsupported_version", "implausible_position", "implausible_battery".
  [[nodiscard]] const std::map<std::string, std::uint64_t>& refusals() const { return refusals_; }

 private:
  RegistryOutcome refuse(const std::string& kind, VehicleView* v, std::string reason);
  /// A parse failure: "too_large" when a limit was crossed, else "bad_message".
  RegistryOutcome refuseUnread(VehicleView* v, const Error& e);
  /// Why a parsed state is not plausible (version, position, battery), with its kind; nothing if it is.
  [[nodiscard]] std::optional<std::pair<std::string, std::string>> implausible(const State& s) const;
  bool setHealth(VehicleView& v, VehicleHealth h, std::string reason);

  std::string interface_;
  std::string map_id_;
  RegistryLimits limits_;
  std::map<std::string, VehicleView> vehicles_;         // by robot id
  std::map<std::string, std::string> by_topic_prefix_;  // "uagv/v2/m/s/" -> robot id
  std::map<std::string, std::uint64_t> refusals_;
};

}  // namespace fleet::vda5050
