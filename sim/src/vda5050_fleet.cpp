#include "fleet/sim/vda5050_fleet.hpp"

#include <cmath>

#include "fleet/vda5050/header.hpp"

namespace fleet::sim {

Vda5050FleetConfig readVda5050FleetConfig(Config c) {
  Vda5050FleetConfig out;
  c.rejectUnknownKeys({"broker", "interface", "manufacturer", "map_id", "protective_field", "vehicles"});
  auto broker = c.child("broker", true);
  broker.rejectUnknownKeys({"host", "port", "ca_file"});
  out.ca_file = broker.string("ca_file", "");
  out.host = broker.string("host", out.host);
  out.port = static_cast<int>(broker.requireInteger("port", {1, 65535}));
  out.interface_name = c.string("interface", out.interface_name);
  out.manufacturer = c.string("manufacturer", out.manufacturer);
  out.map_id = c.string("map_id", out.map_id);
  out.protective_field = c.number("protective_field", out.protective_field, {0.0, 10.0});
  for (auto& v : c.array("vehicles", true)) {
    v.rejectUnknownKeys({"robot", "password"});
    out.vehicles.push_back({v.requireString("robot"), v.requireString("password")});
  }
  for (const auto& s : {out.interface_name, out.manufacturer}) {
    if (s.empty() || s.find_first_of("/#+") != std::string::npos) {
      c.problem("manufacturer", "interface and manufacturer must be non-empty without '/', '#' or '+'");
    }
  }
  c.finish();
  return out;
}

Expected<std::unique_ptr<Vda5050Fleet>> Vda5050Fleet::start(const Vda5050FleetConfig& config,
                                                            const World& world) {
  auto fleet = std::make_unique<Vda5050Fleet>();
  for (const auto& v : config.vehicles) {
    const int idx = world.robotIndex(v.robot);
    if (idx < 0) {
      return unexpected("vda5050.unknown_robot", "vda5050: the scenario has no robot '" + v.robot + "'");
    }
    const auto& spec = world.scenario().robots[static_cast<std::size_t>(idx)];
    Vda5050VehicleConfig vc;
    vc.manufacturer = config.manufacturer;
    vc.serial = v.robot;
    vc.mapId = config.map_id;
    vc.maxSpeed = spec.limits.vMax;
    vc.maxTurnRate = spec.limits.omegaMax;
    vc.width = 2.0 * spec.radius;
    vc.length = 2.0 * spec.radius;
    vc.protectiveField = config.protective_field;
    Vda5050LinkOptions lo;
    lo.host = config.host;
    lo.port = config.port;
    lo.interface_name = config.interface_name;
    lo.manufacturer = config.manufacturer;
    lo.serial = v.robot;
    lo.username = config.manufacturer + "-" + v.robot;
    lo.password = v.password;
    lo.tls_ca_file = config.ca_file;
    auto link = Vda5050Link::start(lo);
    if (!link) {
      return unexpected(link.error());
    }
    fleet->members_.push_back(
        {static_cast<std::size_t>(idx),
         std::make_unique<Vda5050Vehicle>(vc, world.robots()[static_cast<std::size_t>(idx)].pose),
         std::move(*link), false});
  }
  return fleet;
}

bool Vda5050Fleet::controls(std::size_t robot) const {
  for (const auto& m : members_) {
    if (m.robot == robot) {
      return true;
    }
  }
  return false;
}

std::uint64_t Vda5050Fleet::baseStarvedStops() const {
  std::uint64_t n = 0;
  for (const auto& m : members_) {
    n += m.vehicle->baseStarvedStops();
  }
  return n;
}

void Vda5050Fleet::step(World& world, double now_s, std::int64_t stamp_ns) {
  for (auto& m : members_) {
    auto in = m.link->take(stamp_ns);
    for (auto& r : in.refused) {
      ++counters_.refused_messages;
      warnings_.push_back(m.vehicle->config().serial + ": " + r);
    }
    for (const auto& o : in.orders) {
      const auto verdict = m.vehicle->onOrder(o);
      if (verdict.decision == vda5050::OrderDecision::kReject) {
        ++counters_.rejected_orders;
        warnings_.push_back(m.vehicle->config().serial + ": order '" + o.orderId + "' update " +
                            std::to_string(o.orderUpdateId) + " rejected (" + verdict.errorType +
                            "): " + verdict.description);
      }
    }
    m.vehicle->senseBattery(world.robots()[m.robot].battery, world.atCharger(m.robot));
    for (const auto& ia : in.instant_actions) {
      m.vehicle->onInstantActions(ia);
    }
    world.setChargeSwitch(m.robot, m.vehicle->charging());
    const auto& pose = world.robots()[m.robot].pose;
    bool person = false;
    bool warned = false;
    for (const auto& h : world.humans()) {
      person = person || m.vehicle->inProtectiveField(pose, h.p.x, h.p.y, h.r);
      warned = warned || (m.vehicle->config().personApproachSpeed > 0.0 &&
                          m.vehicle->inWarningField(pose, h.p.x, h.p.y, h.r));
    }
    // A safety scanner sees machines too: a vehicle driving into another robot stops as it would
    // for a person (a mixed run had two vehicles overlap by 0.34 m when their orders fell out of
    // step with the traffic manager's releases).
    for (std::size_t j = 0; j < world.robots().size() && !person; ++j) {
      const auto& q = world.robots()[j].pose;
      person = j != m.robot && m.vehicle->machineInField(pose, q.x, q.y, world.scenario().robots[j].radius);
    }
    const auto cmd = m.vehicle->step(now_s, pose, person, warned);
    world.command(m.robot, cmd.v, cmd.w);
    if (const auto stamp = m.vehicle->takeMotionStart()) {
      if (const auto sent = vda5050::parseIsoTimestamp(*stamp)) {
        order_to_motion_ns_.push_back(stamp_ns - *sent);
      } else {
        ++untimed_;
      }
    }
    if (m.link->connected()) {
      if (!m.factsheet_sent || m.vehicle->takeFactsheetRequest()) {
        m.factsheet_sent = m.link->publish(m.vehicle->factsheet(stamp_ns));
      }
      if (m.vehicle->stateDue(now_s) && m.link->publish(m.vehicle->takeState(now_s, stamp_ns))) {
        ++counters_.states_sent;
      }
    }
  }
}

}  // namespace fleet::sim
