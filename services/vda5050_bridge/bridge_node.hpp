#pragma once

// The VDA 5050 bridge without its DDS and MQTT wiring: for each configured vehicle it plays the
// part a robot agent plays for our own robots. Task assignments and the traffic manager's releases
// come in; orders and instant actions go out to the vehicle; the vehicle's state becomes the
// robot's RobotState, TrafficProgress and TaskStatus.
//
//  - Releases: the latest release of a vehicle is turned into an order or an update
//    (vda5050::OrderBuilder) whenever it adds to what was sent; a release ending at the goal
//    carries the goal's pick or drop action.
//  - Goals: a goal is reached when its action finished (pick, drop) or, without one, when the
//    vehicle stands on the goal's node with nothing left of its order.
//  - Idle: without a task the vehicle's goal is where it was first seen (its parking place), so the
//    traffic manager takes it home and out of the way, as robot agents return home.
//  - New orders start where the vehicle's latest state says it is (vda5050::startAtVehicle): at its
//    last node, put in front of the release when the release begins at a neighbour of it.
//  - Rejections (vda5050::findOrderRejection): an order or update the vehicle rejects, or does not
//    take within order_ack_timeout_s, is logged with the vehicle's reason and built again from its
//    latest state (a new order from its last node; an update from the base end of the update it
//    has), after a back-off that doubles. After order_retries failed retries the robot is reported
//    blocked to the traffic manager until a changed release or task gives it a new chance.
//  - Charging: at a charge goal's node, with nothing left of its order, the vehicle is sent
//    startCharging (again, with a fresh action id, when it does not charge within 5 s or answers
//    FAILED; after three the task fails with its reason); it reports mode Charging and holds its
//    node while its state says charging, until the fleet manager ends the task (charged to its
//    target) or the goal's duration from its arrival runs out (then the bridge ends the goal, as a
//    robot agent does). Whenever the vehicle charges with no charge
//    goal of its own (the task ended or changed) it is sent stopCharging, and no order goes out
//    until it reports charging false (VDA 5050 2.1, 6.8.1: stopCharging comes before a new order).
//    A startCharging that FAILED fails the task with the vehicle's reason.
//  - Footprint: a vehicle joins the fleet only once its factsheet and the roadmap are known and its footprint
//    (vda5050::footprint: the disc that holds it at every heading) fits in the robot disc the
//    traffic manager's roadmap conflicts were computed for (Roadmap.robot_radius): a larger
//    vehicle would touch others the plan keeps apart. Until then, or when it does not fit, it is
//    refused with a logged reason: no RobotState (the fleet manager gives it no task), no order,
//    and TrafficProgress `follows: false` (the traffic manager plans round it as an obstacle).
//    Without a factsheet the bridge asks for one (factsheetRequest, every 30 s).
//  - Health (vda5050::VehicleRegistry): a vehicle that is not online (MANUAL, a FATAL error, a
//    message that fails the checks, its last will) publishes no RobotState, so the fleet manager
//    loses it and re-queues its task as for our robots, and its TrafficProgress says it does not
//    follow releases, so the traffic manager plans around it.

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "fleet/core/epoch_fence.hpp"
#include "fleet/messages/messages.hpp"
#include "fleet/vda5050/order_builder.hpp"
#include "fleet/vda5050/order_start.hpp"
#include "fleet/vda5050/vehicle_registry.hpp"

namespace fleet::vdabridge {

struct BridgeSettings {
  std::string interface_name = "uagv";
  std::string map_id;
  std::vector<vda5050::VehicleEntry> vehicles;
  double allowed_deviation = 0.2;  // m, the orders' allowedDeviationXY
  int order_retries = 3;           // re-sends of an order the vehicle rejected before it is reported blocked
  double retry_backoff_s = 1.0;    // wait before the first re-send; doubles with each
  double order_ack_timeout_s = 10.0;  // an order neither taken nor rejected by then counts as rejected
  // A vehicle its protective field has stopped this long, holding base beyond its next node, has
  // its order cancelled: then it can be reported blocked and planned round (as our robots are
  // after 3 s held by a person) without driving on into nodes given to others.
  double field_cancel_s = 3.0;
  /// Refused at the edge, counted by kind: messages larger than this (the broker's
  /// message_size_limit by default), JSON nested or sized past the message limits, a state of a
  /// protocol version other than 2.0/2.1, an agvPosition off the site (the roadmap's extent and
  /// `site_margin` m), a batteryCharge outside 0..100.
  std::size_t max_message_bytes = 256 * 1024;
  double site_margin = 50.0;
};

struct MqttMessage {
  std::string topic;
  std::string payload;
  int qos = 0;
  bool retain = false;
};

struct BridgeOutbox {
  std::vector<MqttMessage> mqtt;
  std::vector<msg::RobotState> states;
  std::vector<msg::TrafficProgress> progress;
  std::vector<msg::TaskStatus> statuses;
  std::vector<std::string> warnings;
  /// Rare and each worth reading (a vehicle joins or is refused): logged without rate limit.
  std::vector<std::string> notices;
};

struct BridgeCounters {
  std::uint64_t orders = 0;
  std::uint64_t updates = 0;
  std::uint64_t cancels = 0;
  std::uint64_t refused_messages = 0;
  std::uint64_t cannot_stitch = 0;
  std::uint64_t rejected = 0;       // orders and updates the vehicle rejected or did not take
  std::uint64_t gave_up = 0;        // times a vehicle was reported blocked after its retries
  std::uint64_t field_cancels = 0;  // orders cancelled because the vehicle's field held it (in `cancels` too)
  std::uint64_t refused_vehicles = 0;  // times a vehicle was refused (no factsheet, too large)
  std::uint64_t charges = 0;           // startCharging sent
  std::uint64_t charge_failures = 0;   // startCharging the vehicle answered FAILED
  std::uint64_t charge_stops = 0;      // stopCharging sent
  /// Times a vehicle stopped at the end of its order's base (newBaseRequest) although its release
  /// from the traffic manager went further: an update that had not reached it (bridge or broker
  /// latency). The traffic manager counts the stops its own releases cause (base ends).
  std::uint64_t late_updates = 0;
  /// TaskAssignments dropped because a fleet manager of a newer lease epoch had spoken (EpochFence).
  std::uint64_t stale_epoch = 0;
};

class BridgeNode {
 public:
  explicit BridgeNode(BridgeSettings settings);

  void onMqtt(const std::string& topic, const std::string& payload, BridgeOutbox& out);
  void onAssignment(const msg::TaskAssignment& a, std::int64_t nowNs, BridgeOutbox& out);
  void onRelease(const msg::TrafficRelease& r);
  /// The traffic manager's roadmap: where a new order may put the vehicle's last node in front.
  void onRoadmap(const msg::Roadmap& m);
  /// Orders for new releases, RobotState and TrafficProgress of every vehicle, task progress.
  void tick(std::int64_t nowNs, BridgeOutbox& out);

  [[nodiscard]] const BridgeCounters& counters() const { return counters_; }
  [[nodiscard]] const vda5050::VehicleRegistry& registry() const { return registry_; }
  [[nodiscard]] bool handles(const std::string& robot_id) const { return vehicles_.contains(robot_id); }

 private:
  struct Vehicle {
    Vehicle(vda5050::VehicleEntry e, vda5050::OrderBuilder b) : entry(std::move(e)), builder(std::move(b)) {}
    vda5050::VehicleEntry entry;
    vda5050::OrderBuilder builder;
    bool has_order = false;
    int orders_started = 0;
    std::optional<msg::TrafficRelease> release;
    std::string task_id;
    std::uint32_t revision = 0;
    std::int32_t priority = 0;  ///< the task's, passed to the traffic manager
    std::vector<msg::Goal> goals;
    std::size_t goal = 0;
    bool paused = false;
    msg::TaskState reported = msg::TaskState::Queued;
    std::size_t reported_goal = 0;     // the goal of the last status sent (a new stop is reported)
    std::int64_t dwell_since_ns = -1;  // at a goal that dwells without an action (a wait) from then
    bool cancel_sent = false;
    std::uint32_t instant_header = 0;
    std::optional<Pose2> home;  // where it was first seen: it parks there when it has no task
    // The order or update last sent, until the vehicle's state shows it taken or rejected.
    bool awaiting = false;
    std::uint32_t sent_update = 0;
    std::int64_t sent_ns = 0;
    int failures = 0;  // orders in a row it rejected (or none could be built)
    std::int64_t retry_ns = 0;
    bool gave_up = false;              // retries spent: reported blocked
    std::int64_t field_since_ns = -1;  // its protective field has stopped it since then
    bool field_cancelled = false;      // its order was cancelled for that: no new one until it is clear
    // The release held when that order was cancelled: the traffic manager may have taken back all
    // of it but its first two nodes since (it holds a blocked robot there), so until a newer
    // release arrives an order takes no more than those.
    std::optional<std::pair<std::uint32_t, std::uint32_t>> stale_release;  // epoch, seq
    std::string charge_action;             // the startCharging sent for the current goal; empty: none
    std::int64_t charge_arrived_ns = -1;   // it stood at its charge goal from then
    std::int64_t charge_sent_ns = 0;       // the last startCharging went out then
    int charge_attempts = 0;               // startCharging sent at this goal
    int stray_stops = 0;                   // stopCharging sent while it charged on without a charge goal
    std::int64_t charge_stop_ns = -1;      // stopCharging last sent then
    std::string failure;                   // the task failed for this (reported with the status)
    std::string refused = "not seen yet";  // why it may not join the fleet now; empty: it may
    std::int64_t factsheet_asked_ns = -1;  // factsheetRequest last sent then
    bool at_base_end = false;              // its last state said newBaseRequest
  };

  void sendOrder(Vehicle& v, const vda5050::Order& o, std::int64_t nowNs, BridgeOutbox& out);
  void watchOrder(Vehicle& v, const vda5050::State& s, std::int64_t nowNs, BridgeOutbox& out);
  void orderFailed(Vehicle& v, const std::string& why, std::int64_t nowNs, BridgeOutbox& out);
  void freshChance(Vehicle& v);
  /// Sends one instant action; its id is `id`, or "<type>-<header id>" when empty.
  void instant(Vehicle& v, const std::string& type, std::int64_t nowNs, BridgeOutbox& out,
               const std::string& id = {});
  void followRelease(Vehicle& v, const vda5050::VehicleView& view, std::int64_t nowNs, BridgeOutbox& out);
  /// The bridge itself holds the vehicle's next order back (retries spent or backing off, its field
  /// held it, charging): then a stop at its base end is the bridge's doing, not an update that came
  /// late. (A stale release, capped to a held robot's two nodes, is left out at the call site: it
  /// still sends orders.)
  [[nodiscard]] bool holdsOrdersBack(const Vehicle& v, const vda5050::VehicleView& view,
                                     std::int64_t nowNs) const;
  void trackGoals(Vehicle& v, const vda5050::VehicleView& view, std::int64_t nowNs, BridgeOutbox& out);
  /// A charge goal at its node: start charging, watch it, end the goal when its duration is over.
  /// False while the goal goes on.
  bool charged(Vehicle& v, const vda5050::State& s, std::int64_t nowNs, BridgeOutbox& out);
  /// stopCharging to a vehicle that charges without a charge goal of its own.
  void stopStrayCharging(Vehicle& v, const vda5050::State& s, std::int64_t nowNs, BridgeOutbox& out);
  void cancelWhenHeld(Vehicle& v, const vda5050::State& s, std::int64_t nowNs, BridgeOutbox& out);
  void reportTask(Vehicle& v, std::int64_t nowNs, BridgeOutbox& out);
  [[nodiscard]] std::string goalActionId(const Vehicle& v, std::size_t goal) const;
  /// Why the vehicle may not join the fleet now; empty when it may.
  [[nodiscard]] std::string refusal(const vda5050::VehicleView& view) const;
  /// Refusal changes logged; an order of a refused vehicle cancelled; factsheet asked for.
  bool admit(Vehicle& v, const vda5050::VehicleView& view, std::int64_t nowNs, BridgeOutbox& out);

  BridgeSettings settings_;
  vda5050::VehicleRegistry registry_;
  std::map<std::string, Vehicle> vehicles_;  // by robot id
  vda5050::KnownRoadmap roadmap_;
  std::optional<double> roadmap_radius_;  // m: Roadmap.robot_radius (none yet; 0: not stated, not checked)
  BridgeCounters counters_;
  EpochFence managerEpoch_;
};

}  // namespace fleet::vdabridge
