#pragma once

// The robots of a simulation that are VDA 5050 vehicles: each has a Vda5050Vehicle (its own
// controller) and a Vda5050Link (its MQTT connection), and no robot agent. Stepped by the
// simulator's loop, so in lockstep the vehicles step with the simulated world.
//
// Config file (fleet-sim --vda5050 FILE):
//   {"broker": {"host": "127.0.0.1", "port": 18830, "ca_file": ""}, "interface": "uagv",
//    "manufacturer": "fleet-sim", "map_id": "small_warehouse", "protective_field": 1.0,
//    "vehicles": [{"robot": "r3", "password": "..."}, ...]}
// A vehicle's serial number is its robot id; its broker user is "<manufacturer>-<serial>".

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "fleet/core/config.hpp"
#include "fleet/sim/vda5050_link.hpp"
#include "fleet/sim/vda5050_vehicle.hpp"
#include "fleet/sim/world.hpp"

namespace fleet::sim {

struct Vda5050FleetConfig {
  std::string host = "127.0.0.1";
  int port = 0;
  std::string ca_file;  // TLS: the CA of the broker's certificate; empty: plain TCP
  std::string interface_name = "uagv";
  std::string manufacturer = "fleet-sim";
  std::string map_id = "warehouse";
  double protective_field = 1.0;
  struct Vehicle {
    std::string robot;
    std::string password;
  };
  std::vector<Vehicle> vehicles;
};

/// Reads the config; throws ConfigError naming every bad key.
Vda5050FleetConfig readVda5050FleetConfig(Config config);

struct Vda5050FleetCounters {
  std::uint64_t refused_messages = 0;  // unreadable orders or instant actions
  std::uint64_t rejected_orders = 0;   // readable, refused by the order rules
  std::uint64_t states_sent = 0;
};

class Vda5050Fleet {
 public:
  /// Fails when a vehicle names a robot the scenario does not have, or a link cannot start.
  static Expected<std::unique_ptr<Vda5050Fleet>> start(const Vda5050FleetConfig& config, const World& world);

  [[nodiscard]] bool controls(std::size_t robot) const;
  /// Messages in, one control step per vehicle (commands into the world), messages out.
  /// `now_s` is simulated time; `stamp_ns` goes into the messages' timestamps.
  void step(World& world, double now_s, std::int64_t stamp_ns);

  [[nodiscard]] const Vda5050FleetCounters& counters() const { return counters_; }
  [[nodiscard]] std::uint64_t baseStarvedStops() const;
  /// Order-to-motion latencies in ns: from an order's header timestamp to the step at which the
  /// vehicle it reached, standing idle, started to move on it (stamp_ns of that step). Meaningful
  /// when the bridge and the simulator share a clock (wall clock runs).
  [[nodiscard]] const std::vector<std::int64_t>& orderToMotionNs() const { return order_to_motion_ns_; }
  /// Orders whose timestamp could not be read (not timed).
  [[nodiscard]] std::uint64_t untimedOrders() const { return untimed_; }
  /// Warnings for the log since the last call (refused messages, rejected orders).
  std::vector<std::string> takeWarnings() { return std::exchange(warnings_, {}); }

 private:
  struct Member {
    std::size_t robot = 0;
    std::unique_ptr<Vda5050Vehicle> vehicle;
    std::unique_ptr<Vda5050Link> link;
    bool factsheet_sent = false;
  };
  std::vector<Member> members_;
  Vda5050FleetCounters counters_;
  std::vector<std::string> warnings_;
  std::vector<std::int64_t> order_to_motion_ns_;
  std::uint64_t untimed_ = 0;
};

}  // namespace fleet::sim
