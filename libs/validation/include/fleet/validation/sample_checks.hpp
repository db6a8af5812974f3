#pragma once

// What every service checks in a sample before it acts on it: finite and plausible numbers, sizes
// within bounds, ids of the allowed form, enums of known values, task/goal structure, text in
// UTF-8. Free text (a robot's error, an event's reason, an ack's detail) is repaired rather than
// refused: the transition it travels with matters more than the words. docs/architecture.md lists
// what each service refuses.

#include <cstddef>
#include <cstdint>
#include <optional>

#include "fleet/messages/messages.hpp"
#include "fleet/validation/rejections.hpp"

namespace fleet::validation {

/// |x|, |y| of any position in the map frame [m]: far beyond any warehouse, well inside the range
/// where double arithmetic on them stays exact to the millimetre.
inline constexpr double kMaxCoordinate = 1e6;
/// Wheel travel since a driver started [m]: 10^9 m is 30 years at 1 m/s.
inline constexpr double kMaxWheelTotal = 1e9;
/// Wheel travel in one sensor frame [m].
inline constexpr double kMaxWheelStep = 100.0;
/// Speeds [m/s, rad/s] and a robot's radius [m].
inline constexpr double kMaxSpeed = 100.0;
inline constexpr double kMaxRadius = 100.0;
/// A goal's dwell [s] (a charge may last long; the manager's charge_max_s is at most a day).
inline constexpr double kMaxDwellS = 7.0 * 86400.0;
/// Bounds of the sequences the IDL used to leave open (idl/fleet.idl says the same).
inline constexpr std::size_t kMaxRiskRuns = std::size_t{1} << 22;
inline constexpr std::size_t kMaxRiskRegions = std::size_t{1} << 14;
inline constexpr std::size_t kMaxRingPoints = std::size_t{1} << 14;
inline constexpr std::size_t kMaxRingHoles = 256;
inline constexpr std::size_t kMaxBodies = std::size_t{1} << 16;
inline constexpr std::size_t kMaxContacts = std::size_t{1} << 16;
inline constexpr std::size_t kMaxRoadmapNodes = std::size_t{1} << 20;
inline constexpr std::size_t kMaxRoadmapEdges = std::size_t{1} << 22;
/// A roadmap node's kind: 0 lane, 1 station, 2 approach, 3 queue, 4 parking, 5 charger.
inline constexpr std::uint8_t kMaxRoadmapNodeKind = 6;
/// Cells of a risk map (as the agent's RiskField accepts).
inline constexpr std::size_t kMaxRiskCells = std::size_t{1} << 26;

std::optional<Rejection> check(const msg::Task& m);
std::optional<Rejection> check(const msg::TaskAck& m);
std::optional<Rejection> check(const msg::TaskEvent& m);
std::optional<Rejection> check(const msg::TaskAssignment& m);
std::optional<Rejection> check(const msg::TaskStatus& m);
std::optional<Rejection> check(const msg::RobotState& m);
std::optional<Rejection> check(const msg::PredictedDiscs& m);
/// Every person's position, velocity and radius finite and plausible, at most msg::kMaxPeopleSeen.
/// Whether the robot is one the reader knows is the reader's to judge.
std::optional<Rejection> check(const msg::PeopleSeen& m);
std::optional<Rejection> check(const msg::RiskMap& m);
std::optional<Rejection> check(const msg::SensorFrame& m);
std::optional<Rejection> check(const msg::VelocityCommand& m);
std::optional<Rejection> check(const msg::GroundTruth& m);
std::optional<Rejection> check(const msg::TrafficRelease& m);
std::optional<Rejection> check(const msg::TrafficProgress& m);
std::optional<Rejection> check(const msg::TrafficClosure& m);
std::optional<Rejection> check(const msg::Roadmap& m);

/// Replaces invalid UTF-8 in the free-text fields; true when anything changed.
bool repairText(msg::TaskStatus& m);
bool repairText(msg::TaskEvent& m);
bool repairText(msg::TaskAck& m);

/// The topic name a type with free text travels on (for counting repairs).
const char* topicOf(const msg::TaskStatus&);
const char* topicOf(const msg::TaskEvent&);
const char* topicOf(const msg::TaskAck&);

/// The edge of a service: repairs free text where the type has any, checks, counts. True when the
/// sample may be used; `why` (optional) gets the rejection.
template <class T>
bool admit(T& sample, Rejections& counters, Rejection* why = nullptr) {
  if constexpr (requires { repairText(sample); }) {
    if (repairText(sample)) {
      counters.repaired(topicOf(sample));
    }
  }
  auto r = check(sample);
  if (!r) {
    return true;
  }
  counters.count(*r);
  if (why != nullptr) {
    *why = std::move(*r);
  }
  return false;
}

}  // namespace fleet::validation
