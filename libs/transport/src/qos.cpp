#include "fleet/transport/qos.hpp"

#include <dds/dds.h>

#include <string>

namespace fleet::transport {

dds_qos_t* QosProfile::make() const {
  dds_qos_t* q = dds_create_qos();
  if (reliable) {
    dds_qset_reliability(q, DDS_RELIABILITY_RELIABLE, DDS_MSECS(maxBlockingMs));
  } else {
    dds_qset_reliability(q, DDS_RELIABILITY_BEST_EFFORT, 0);
  }
  dds_qset_durability(q, transientLocal ? DDS_DURABILITY_TRANSIENT_LOCAL : DDS_DURABILITY_VOLATILE);
  if (depth <= 0) {
    dds_qset_history(q, DDS_HISTORY_KEEP_ALL, 0);
  } else {
    dds_qset_history(q, DDS_HISTORY_KEEP_LAST, depth);
  }
  if (livelinessLeaseMs > 0) {
    dds_qset_liveliness(q, DDS_LIVELINESS_AUTOMATIC, DDS_MSECS(livelinessLeaseMs));
  }
  return q;
}

namespace qos {
QosProfile taskRequest() {
  return {true, true, 1, 0, 1000};
}
QosProfile taskAck() {
  return {true, false, 4, 0, 1000};
}
QosProfile taskEvent() {
  return {true, true, 32, 0, 1000};
}
QosProfile assignment() {
  return {true, true, 1, 0, 1000};
}
QosProfile taskStatus() {
  return {true, false, 16, 0, 1000};
}
QosProfile robotState() {
  return {false, false, 1, 1000, 0};
}
QosProfile predictedDiscs() {
  return {false, false, 1, 0, 0};
}
QosProfile peopleSeen() {
  return {false, false, 1, 0, 0};
}
QosProfile riskMap() {
  return {true, true, 1, 0, 100};
}
QosProfile sensor(bool lockstep) {
  return lockstep ? QosProfile{true, false, 4, 0, 1000} : QosProfile{false, false, 1, 0, 0};
}
QosProfile command(bool lockstep) {
  return lockstep ? QosProfile{true, false, 4, 0, 1000} : QosProfile{false, false, 1, 0, 0};
}
QosProfile clock() {
  return {true, false, 1, 0, 1000};
}
QosProfile groundTruth() {
  return {true, false, 64, 0, 1000};
}
QosProfile roadmap() {
  return {true, true, 1, 0, 1000};
}
QosProfile trafficRelease() {
  return {true, true, 1, 0, 1000};
}
QosProfile trafficProgress() {
  return {true, true, 1, 0, 1000};
}
QosProfile trafficClosure() {
  return {true, true, 1, 0, 1000};
}

bool byName(std::string_view name, QosProfile& out) {
  const std::string n(name);
  if (n == "task_request")
    out = taskRequest();
  else if (n == "task_event")
    out = taskEvent();
  else if (n == "assignment")
    out = assignment();
  else if (n == "task_status")
    out = taskStatus();
  else if (n == "robot_state")
    out = robotState();
  else if (n == "predicted_discs")
    out = predictedDiscs();
  else if (n == "risk_map")
    out = riskMap();
  else if (n == "sensor")
    out = sensor(false);
  else if (n == "sensor_lockstep")
    out = sensor(true);
  else if (n == "command")
    out = command(false);
  else if (n == "command_lockstep")
    out = command(true);
  else if (n == "clock")
    out = clock();
  else if (n == "ground_truth")
    out = groundTruth();
  else if (n == "roadmap")
    out = roadmap();
  else if (n == "traffic_release")
    out = trafficRelease();
  else if (n == "traffic_progress")
    out = trafficProgress();
  else if (n == "traffic_closure")
    out = trafficClosure();
  else if (n == "people_seen")
    out = peopleSeen();
  else
    return false;
  return true;
}
}  // namespace qos

}  // namespace fleet::transport
