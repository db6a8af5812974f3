#pragma once

// A simulated VDA 5050 vehicle: no robot agent, its own simple controller. It follows the released
// nodes of its order, stops at the last base node until the order is extended, stops for a person
// in its protective field as a safety scanner would, runs pick and drop actions at nodes, obeys
// pause, resume and cancel, switches its charging on and off (startCharging / stopCharging, on a
// charger only; no orders while charging), and accepts or rejects orders by the specification's
// rules (vda5050/order_rules.hpp). No MQTT here: the simulator carries the messages.

#include <algorithm>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "fleet/core/pose2.hpp"
#include "fleet/vda5050/factsheet.hpp"
#include "fleet/vda5050/instant_actions.hpp"
#include "fleet/vda5050/order.hpp"
#include "fleet/vda5050/order_rules.hpp"
#include "fleet/vda5050/state.hpp"

namespace fleet::sim {

struct Vda5050VehicleConfig {
  std::string manufacturer = "fleet-sim";
  std::string serial;
  std::string mapId;
  double maxSpeed = 1.0;         // m/s
  double maxTurnRate = 1.5;      // rad/s
  double nodeTolerance = 0.15;   // m; a node's allowedDeviationXY wins when larger
  double protectiveField = 1.0;  // m ahead of the front at standstill; a person inside stops the vehicle
  /// The field reaches this much beyond each side [m], and grows ahead and to each side by the
  /// braking distance at its speed (v² / 2·brakeDecel), as a safety scanner's speed-switched
  /// fields do. A
  /// field only as wide as the vehicle and 1 m long let a person walking in from the side reach a
  /// vehicle at 0.9 m/s (a 3.6 cm contact in a 20-robot mixed run).
  double fieldSideMargin = 0.3;
  double brakeDecel = 1.0;  // m/s²
  /// The warning field: a person inside it slows the vehicle to `warningSpeed`. It reaches ahead
  /// of the protective field by the way a person walking towards the vehicle at
  /// `personApproachSpeed` covers while it brakes from its speed (ISO 13855 sizes safety distances
  /// for 1.6 m/s). Off by default (0): with 1.6 m/s the mixed 20-robot benchmark did ~80 % of the
  /// all-agent tasks instead of ~89 % (vehicles crawl behind people in the aisles), and with the
  /// fields sized on the measured speed (below) it had no contact without it either
  /// (docs/benchmarks.md, 2026-11-28).
  double warningSpeed = 0.3;         // m/s
  double personApproachSpeed = 0.0;  // m/s; 1.6 for ISO 13855's approach speed
  double width = 0.6;
  double length = 0.6;
  double stateInterval = 1.0;   // s between state messages without an event
  double actionDuration = 2.0;  // s a pick or drop takes
};

struct VehicleCommand {
  double v = 0.0;
  double w = 0.0;
};

class Vda5050Vehicle {
 public:
  Vda5050Vehicle(Vda5050VehicleConfig config, Pose2 start);

  /// Accepts (new, stitched update), discards a duplicate, or rejects with an error in the state.
  vda5050::OrderVerdict onOrder(const vda5050::Order& order);
  void onInstantActions(const vda5050::InstantActions& message);
  /// What its battery management sees before a step: state of charge 0..1 and whether its
  /// charging contacts touch a charger's.
  void senseBattery(double stateOfCharge, bool atCharger);
  /// Its charging is switched on (startCharging taken, stopCharging not yet).
  [[nodiscard]] bool charging() const { return charging_; }
  /// One control step at simulated time `now_s` from the true pose; `person_in_field` is what the
  /// safety scanner sees, `person_in_warning_field` whether it sees one in its warning field.
  VehicleCommand step(double now_s, const Pose2& pose, bool person_in_field,
                      bool person_in_warning_field = false);

  /// True when a state message is due: the interval passed or something happened.
  [[nodiscard]] bool stateDue(double now_s) const;
  /// The state message now; resets the interval and the pending event.
  vda5050::State takeState(double now_s, std::int64_t stamp_ns);
  /// True once after a factsheetRequest instant action.
  bool takeFactsheetRequest();
  [[nodiscard]] vda5050::Factsheet factsheet(std::int64_t stamp_ns) const;
  void setOperatingMode(std::string mode);

  [[nodiscard]] const Vda5050VehicleConfig& config() const { return config_; }
  /// Times the vehicle stopped at the end of its base with horizon nodes left (the base was not
  /// extended in time).
  [[nodiscard]] std::uint64_t baseStarvedStops() const { return starved_stops_; }
  [[nodiscard]] bool paused() const { return paused_; }
  [[nodiscard]] const std::string& lastNodeId() const { return last_node_id_; }
  /// Once, at the step where the vehicle starts moving on an order or update that reached it while
  /// it stood with nothing to do: that order's header timestamp (order-to-motion latency; the
  /// controller's command counts, before the protective field's stop).
  std::optional<std::string> takeMotionStart() { return std::exchange(motion_started_, std::nullopt); }

  /// Whether a point (a person) is inside the protective field of a vehicle at `pose`: a
  /// rectangle ahead of its front, the vehicle's width plus fieldSideMargin plus the braking
  /// distance at its speed each side, as long as
  /// `protectiveField` plus the braking distance at its speed (the larger of the last commanded
  /// and the measured one).
  [[nodiscard]] bool inProtectiveField(const Pose2& pose, double px, double py, double radius) const;
  /// Whether a person is inside the warning field: as the protective field, longer by
  /// personApproachSpeed × the time to brake from its speed.
  [[nodiscard]] bool inWarningField(const Pose2& pose, double px, double py, double radius) const;
  /// Whether another vehicle's body (a disc) is inside the short field a scanner keeps for
  /// machines: ahead of the front by the braking distance at its speed (as above) plus
  /// kMachineFieldM, the vehicle's width plus kMachineSideM each side. Shorter than the people's
  /// field so vehicles can follow one another at the roadmap's following distance.
  [[nodiscard]] bool machineInField(const Pose2& pose, double px, double py, double radius) const;
  static constexpr double kMachineFieldM = 0.15;
  static constexpr double kMachineSideM = 0.05;

 private:
  [[nodiscard]] bool actionsRunning() const;
  [[nodiscard]] vda5050::OrderProgress progress() const;
  void reachNode(double now_s);
  void runNodeActions(double now_s);
  void cancel();
  vda5050::ActionState* actionState(const std::string& id);
  void event() { event_ = true; }

  Vda5050VehicleConfig config_;
  Pose2 pose_;
  std::optional<vda5050::Order> order_;
  std::size_t next_ = 0;  // index in order_->nodes of the node to reach next
  std::string last_node_id_;
  std::uint32_t last_node_seq_ = 0;
  bool paused_ = false;
  bool driving_ = false;
  bool field_violation_ = false;
  bool waiting_for_base_ = false;
  bool charging_ = false;
  bool at_charger_ = false;
  double battery_ = 1.0;
  std::string operating_mode_ = "AUTOMATIC";
  std::vector<vda5050::ActionState> action_states_;
  std::vector<std::pair<std::string, double>> running_;  // node action id, finish time
  std::vector<vda5050::VehicleError> errors_;
  std::uint32_t header_id_ = 0;
  double last_state_s_ = -1e9;
  bool event_ = true;
  bool factsheet_requested_ = false;
  std::uint64_t starved_stops_ = 0;
  double distance_since_node_ = 0.0;
  VehicleCommand last_command_;
  /// Speed over the last step from the poses it was given: the fields switch on the larger of
  /// this and the commanded speed (braking, the command drops at once, the vehicle does not).
  double measured_speed_ = 0.0;
  double last_step_s_ = -1.0;
  [[nodiscard]] double fieldSpeed() const { return std::max(std::abs(last_command_.v), measured_speed_); }
  std::optional<std::string> motion_pending_;  // header timestamp of the order it should start on
  std::optional<std::string> motion_started_;
};

}  // namespace fleet::sim
