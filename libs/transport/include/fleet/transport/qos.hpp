#pragma once

#include <cstdint>
#include <string_view>

struct dds_qos;

namespace fleet::transport {

/// The QoS settings we use, as one value; `make()` builds the Cyclone QoS object.
struct QosProfile {
  bool reliable = true;
  bool transientLocal = false;
  std::int32_t depth = 1;              // keep-last depth; 0 = keep-all
  std::int64_t livelinessLeaseMs = 0;  // 0 = Cyclone's default (infinite)
  std::int64_t maxBlockingMs = 100;    // how long a reliable write may wait for room

  /// Caller owns the result (dds_delete_qos).
  [[nodiscard]] dds_qos* make() const;
};

/// Named profiles, one per topic family of DESIGN.md §3.
namespace qos {
QosProfile taskRequest();           // Task: reliable, transient-local, keep-last 1 per key
QosProfile taskAck();               // TaskAck: reliable, volatile, keep-last 4 per request
QosProfile taskEvent();             // TaskEvent: reliable, transient-local, keep-last 32 per key
QosProfile assignment();            // TaskAssignment: reliable, transient-local, keep-last 1
QosProfile taskStatus();            // TaskStatus: reliable, keep-last 16
QosProfile robotState();            // RobotState: best-effort, keep-last 1, liveliness lease 1 s
QosProfile predictedDiscs();        // best-effort, keep-last 1
QosProfile peopleSeen();            // PeopleSeen: best-effort, keep-last 1 per robot
QosProfile riskMap();               // reliable, transient-local, keep-last 1
QosProfile sensor(bool lockstep);   // SensorFrame: best-effort, reliable in lockstep
QosProfile command(bool lockstep);  // VelocityCommand: likewise
QosProfile clock();                 // Clock / StepDone: reliable, keep-last 1 (per key)
QosProfile groundTruth();           // reliable, keep-last 64
QosProfile roadmap();               // reliable, transient-local, keep-last 1
QosProfile trafficRelease();        // reliable, transient-local, keep-last 1 per robot
QosProfile trafficProgress();       // reliable, transient-local, keep-last 1 per robot
QosProfile trafficClosure();        // reliable, transient-local, keep-last 1 per closure id
/// Looks a profile up by name (the names above, snake_case); false when unknown.
bool byName(std::string_view name, QosProfile& out);
}  // namespace qos

}  // namespace fleet::transport
