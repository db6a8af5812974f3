// Prints every kind of VDA 5050 message our code sends, one per line as "<topic>\t<json>", made by
// the real producers (the simulated vehicle through a scripted run, the message conversions), for
// tests/vda5050/validate_messages.py to check against the official schemas.

#include <iostream>

#include "bridge_node.hpp"
#include "fleet/sim/vda5050_vehicle.hpp"
#include "fleet/vda5050/connection.hpp"
#include "fleet/vda5050/instant_actions.hpp"
#include "fleet/vda5050/order_builder.hpp"
#include "order_fixtures.hpp"
#include "vehicle_rig.hpp"

using namespace fleet;

namespace {

void print(const char* topic, const nlohmann::json& j) {
  std::cout << topic << '\t' << j.dump() << '\n';
}

}  // namespace

int main() {
  sim::test::Rig rig;
  auto& vehicle = rig.vehicle;
  const auto run = [&](double seconds, bool person) {
    rig.person = person;
    rig.run(seconds, [&] {
      if (vehicle.stateDue(rig.t)) {
        const auto stamp = 1'790'000'000'000'000'000 + static_cast<std::int64_t>(rig.t * 1e9);
        print("state", vda5050::toJson(vehicle.takeState(rig.t, stamp)));
      }
    });
  };
  print("state", vda5050::toJson(vehicle.takeState(rig.t, 0)));  // before any order
  auto order = vda5050::test::lineOrder("o1", 0, 0, 6, 3);
  order.nodes[1].actions.push_back(
      {"pick", "pick-1", "HARD", std::string("load the tote"), {{"stationId", "P-1"}}});
  order.nodes[2].actions.push_back({"drop", "drop-1", "HARD", {}, {{"stationId", "D-1"}}});
  order.edges[0].maxSpeed = 0.8;
  order.edges[0].length = 1.0;
  print("order", vda5050::toJson(order));
  (void)vehicle.onOrder(order);
  run(4.0, false);
  run(1.0, true);                                                     // protective field
  (void)vehicle.onOrder(vda5050::test::lineOrder("o1", 1, 3, 3, 3));  // rejected: an error in the state
  run(15.0, false);
  const auto update = vda5050::test::lineOrder("o1", 1, 2, 4, 3);
  print("order", vda5050::toJson(update));
  (void)vehicle.onOrder(update);
  vda5050::InstantActions ia;
  ia.header = {3, vda5050::isoTimestamp(0), vda5050::kVersion, "fleet-sim", "AGV-1"};
  ia.actions = {{"startPause", "pause-1", "HARD", {}, {}}, {"factsheetRequest", "fs-1", "NONE", {}, {}}};
  print("instantActions", vda5050::toJson(ia));
  vehicle.onInstantActions(ia);
  run(2.0, false);
  if (vehicle.takeFactsheetRequest()) {
    print("factsheet", vda5050::toJson(vehicle.factsheet(0)));
  }
  ia.actions = {{"stopPause", "resume-1", "HARD", {}, {}}, {"cancelOrder", "cancel-1", "HARD", {}, {}}};
  print("instantActions", vda5050::toJson(ia));
  vehicle.onInstantActions(ia);
  run(2.0, false);
  // Charging: refused off a charger (a chargingError in the state), then on one, then stopped.
  vehicle.senseBattery(0.35, false);
  ia.actions = {{"startCharging", "charge.r1-g0", "HARD", {}, {}}};
  print("instantActions", vda5050::toJson(ia));
  vehicle.onInstantActions(ia);
  run(1.0, false);
  vehicle.senseBattery(0.35, true);
  vehicle.onInstantActions(ia);
  run(1.0, false);
  ia.actions = {{"stopCharging", "stopCharging-7", "HARD", {}, {}}};
  print("instantActions", vda5050::toJson(ia));
  vehicle.onInstantActions(ia);
  run(1.0, false);
  for (const char* s : {"ONLINE", "OFFLINE", "CONNECTIONBROKEN"}) {
    print("connection", vda5050::toJson(vda5050::Connection{ia.header, s}));
  }
  // The master control's orders: a release becomes an order, more released nodes an update.
  vda5050::OrderBuilder builder({"fleet-sim", "AGV-1", "small", 0.2});
  vda5050::ReleaseInput r;
  r.base = {{10, 1.0, 2.0}, {11, 2.0, 2.0}};
  r.horizon = {{12, 3.0, 2.0}};
  r.actions = {{11, {"pick", "t1-pick", "HARD", {}, {{"stationId", "P-1"}}}}};
  print("order", vda5050::toJson(*builder.start("t1", r, 0)));
  r.base = {{11, 2.0, 2.0}, {12, 3.0, 2.0}, {13, 4.0, 2.0}};
  r.horizon = {};
  if (const auto up = builder.extend(r, 2, 0); up && up->has_value()) {
    print("order", vda5050::toJson(**up));
  }
  // What the bridge sends: orders for releases, pause, resume and cancel.
  vdabridge::BridgeNode bridge({"uagv", "small", {{"fleet-sim", "AGV-1", "r1"}}, 0.2});
  vdabridge::BridgeOutbox out;
  sim::test::Rig fresh;
  auto st = fresh.vehicle.takeState(0.0, 0);
  st.header.manufacturer = "fleet-sim";
  msg::Roadmap roadmap;
  roadmap.robot_radius = 0.3;
  bridge.onRoadmap(roadmap);
  bridge.onMqtt("uagv/v2/fleet-sim/AGV-1/factsheet", vda5050::toJson(fresh.vehicle.factsheet(0)).dump(), out);
  bridge.onMqtt("uagv/v2/fleet-sim/AGV-1/state", vda5050::toJson(st).dump(), out);
  msg::TaskAssignment assignment;
  assignment.robot_id = "r1";
  assignment.task_id = "t9";
  assignment.goals = {{{2.0, 0.0, 0.0}, "P-1", msg::GoalAction::Load, 3.0}};
  assignment.paused = true;
  bridge.onAssignment(assignment, 0, out);
  assignment.paused = false;
  bridge.onAssignment(assignment, 0, out);
  msg::TrafficRelease release;
  release.robot_id = "r1";
  release.base = {{0, 0.0, 0.0}, {1, 1.0, 0.0}, {2, 2.0, 0.0}};
  release.ends_at_goal = true;
  bridge.onRelease(release);
  bridge.tick(0, out);
  assignment.task_id.clear();
  bridge.onAssignment(assignment, 0, out);
  for (const auto& m : out.mqtt) {
    const auto topic = m.topic.substr(m.topic.rfind('/') + 1);
    std::cout << topic << '\t' << m.payload << '\n';
  }
  return 0;
}
