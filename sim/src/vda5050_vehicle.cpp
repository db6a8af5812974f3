#include "fleet/sim/vda5050_vehicle.hpp"

#include <algorithm>
#include <cmath>

#include "fleet/core/angles.hpp"

namespace fleet::sim {

using namespace fleet::vda5050;

namespace {

// A bend in the route up to this is driven through (at kCornerSpeed m/s on the node); a sharper one
// is stopped at and turned on the spot.
constexpr double kGentleBend = 0.8;  // rad, 46°
constexpr double kCornerSpeed = 0.35;
constexpr double kLookahead = 0.2;       // m along the edge
constexpr double kStandingSpeed = 0.05;  // m/s: below it a vehicle stopped by its field may turn on the spot
bool finished(const ActionState& a) {
  return a.actionStatus == "FINISHED" || a.actionStatus == "FAILED";
}
}  // namespace

Vda5050Vehicle::Vda5050Vehicle(Vda5050VehicleConfig config, Pose2 start)
    : config_(std::move(config)), pose_(start) {}

bool Vda5050Vehicle::actionsRunning() const {
  return std::any_of(action_states_.begin(), action_states_.end(),
                     [](const ActionState& a) { return !finished(a); });
}

OrderProgress Vda5050Vehicle::progress() const {
  OrderProgress p;
  if (order_) {
    p.orderId = order_->orderId;
    p.orderUpdateId = order_->orderUpdateId;
    if (const auto end = baseEnd(*order_)) {
      p.baseEndNodeId = end->nodeId;
      p.baseEndSequenceId = end->sequenceId;
    }
    p.active = next_ < order_->nodes.size() || actionsRunning();
  }
  p.lastNodeId = last_node_id_;
  p.lastNodeSequenceId = last_node_seq_;
  return p;
}

ActionState* Vda5050Vehicle::actionState(const std::string& id) {
  for (auto& a : action_states_) {
    if (a.actionId == id) {
      return &a;
    }
  }
  return nullptr;
}

OrderVerdict Vda5050Vehicle::onOrder(const Order& order) {
  const bool idle = !driving_ && running_.empty() && !paused_;
  auto verdict = judgeOrder(progress(), order);
  if (!order.nodes.empty() && order.nodes.front().nodePosition &&
      order.nodes.front().nodePosition->mapId != config_.mapId &&
      verdict.decision != OrderDecision::kReject) {
    verdict = {OrderDecision::kReject, "noRouteError",
               "order '" + order.orderId + "' is on map '" + order.nodes.front().nodePosition->mapId +
                   "', the vehicle is on '" + config_.mapId + "'"};
  }
  if (operating_mode_ != "AUTOMATIC" && verdict.decision != OrderDecision::kReject) {
    verdict = {OrderDecision::kReject, "orderError", "the vehicle is in " + operating_mode_ + " mode"};
  }
  // VDA 5050 2.1, 6.8.1: charging is stopped "to send a new order"; the vehicle is not ready for
  // one before (a duplicate is still discarded, it changes nothing).
  if (charging_ &&
      (verdict.decision == OrderDecision::kAcceptNew || verdict.decision == OrderDecision::kAcceptUpdate)) {
    verdict = {OrderDecision::kReject, "orderError",
               "order '" + order.orderId + "': the vehicle is charging (stopCharging first)"};
  }
  switch (verdict.decision) {
    case OrderDecision::kAcceptNew: {
      order_ = order;
      next_ = 0;
      action_states_.clear();
      running_.clear();
      errors_.clear();
      waiting_for_base_ = false;
      // The first node is where the vehicle stands (the rules checked it): its state says so from
      // The first message on (the next step reaches it and runs its actions).
      if (!order_->nodes.empty() && !last_node_id_.empty() && order_->nodes.front().nodeId == last_node_id_) {
        last_node_seq_ = order_->nodes.front().sequenceId;
      }
      break;
    }
    case OrderDecision::kAcceptUpdate: {
      const auto reached_seq = next_ > 0 ? order_->nodes[next_ - 1].sequenceId : 0U;
      const bool any_reached = next_ > 0;
      order_ = stitchOrder(*order_, order);
      next_ = 0;
      if (any_reached) {
        while (next_ < order_->nodes.size() && order_->nodes[next_].sequenceId <= reached_seq) {
          ++next_;
        }
      }
      errors_.clear();
      waiting_for_base_ = false;
      break;
    }
    case OrderDecision::kDiscardDuplicate:
      return verdict;
    case OrderDecision::kReject:
      errors_.push_back(
          {verdict.errorType,
           "WARNING",
           verdict.description,
           {{"orderId", order.orderId}, {"orderUpdateId", std::to_string(order.orderUpdateId)}}});
      event();
      return verdict;
  }
  // Order-to-motion: timed when the vehicle stood with nothing to do and the order gives it a
  // released node to drive to (not one it stands on).
  if (idle) {
    for (std::size_t k = next_; k < order_->nodes.size() && order_->nodes[k].released; ++k) {
      const auto& p = order_->nodes[k].nodePosition;
      if (p && std::hypot(p->x - pose_.x, p->y - pose_.y) > config_.nodeTolerance) {
        motion_pending_ = order.header.timestamp;
        break;
      }
    }
  }
  for (const auto& n : order_->nodes) {
    for (const auto& a : n.actions) {
      if (actionState(a.actionId) == nullptr) {
        action_states_.push_back({a.actionId, a.actionType, "WAITING", {}});
      }
    }
  }
  event();
  return verdict;
}

void Vda5050Vehicle::cancel() {
  if (order_) {
    order_->nodes.erase(
        order_->nodes.begin() + static_cast<std::ptrdiff_t>(std::min(next_, order_->nodes.size())),
        order_->nodes.end());
    next_ = order_->nodes.size();
    const std::uint32_t passed = next_ > 0 ? order_->nodes[next_ - 1].sequenceId : 0U;
    std::erase_if(order_->edges, [&](const Edge& e) { return next_ == 0 || e.sequenceId > passed; });
  }
  for (auto& a : action_states_) {
    if (!finished(a)) {
      a.actionStatus = "FAILED";
      a.resultDescription = "cancelled";
    }
  }
  running_.clear();
  waiting_for_base_ = false;
  motion_pending_.reset();
}

void Vda5050Vehicle::onInstantActions(const InstantActions& message) {
  for (const auto& a : message.actions) {
    ActionState s{a.actionId, a.actionType, "FINISHED", {}};
    if (a.actionType == "startPause") {
      paused_ = true;
    } else if (a.actionType == "stopPause") {
      paused_ = false;
    } else if (a.actionType == "cancelOrder") {
      if (!order_ || next_ >= order_->nodes.size()) {
        s.actionStatus = "FAILED";
        s.resultDescription = "no order to cancel";
        errors_.push_back(
            {"noOrderToCancel", "WARNING", std::string("cancelOrder without an active order"), {}});
      } else {
        cancel();
      }
    } else if (a.actionType == "startCharging") {
      // Only standing on a charger with nothing left to drive: charging on the way (a charging
      // lane) is not something this vehicle does.
      std::string why;
      if (!at_charger_) {
        why = "not on a charging spot";
      } else if (driving_ || (order_ && next_ < order_->nodes.size())) {
        why = "the vehicle has an order to drive";
      }
      if (why.empty()) {
        charging_ = true;
      } else {
        s.actionStatus = "FAILED";
        s.resultDescription = why;
        errors_.push_back({"chargingError", "WARNING", "startCharging: " + why, {{"actionId", a.actionId}}});
      }
    } else if (a.actionType == "stopCharging") {
      charging_ = false;  // idempotent: FINISHED when it was not charging either
    } else if (a.actionType == "factsheetRequest") {
      factsheet_requested_ = true;
    } else if (a.actionType == "stateRequest") {
      // The event below sends the state at once.
    } else {
      s.actionStatus = "FAILED";
      s.resultDescription = "instant action '" + a.actionType + "' is not supported";
    }
    if (auto* existing = actionState(a.actionId)) {
      *existing = s;
    } else {
      action_states_.push_back(s);
    }
  }
  event();
}

void Vda5050Vehicle::senseBattery(double stateOfCharge, bool atCharger) {
  battery_ = std::clamp(stateOfCharge, 0.0, 1.0);
  at_charger_ = atCharger;
}

void Vda5050Vehicle::reachNode(double now_s) {
  const auto& n = order_->nodes[next_];
  last_node_id_ = n.nodeId;
  last_node_seq_ = n.sequenceId;
  distance_since_node_ = 0.0;
  ++next_;
  runNodeActions(now_s);
  event();
}

void Vda5050Vehicle::runNodeActions(double now_s) {
  for (const auto& a : order_->nodes[next_ - 1].actions) {
    if (auto* s = actionState(a.actionId); s != nullptr && s->actionStatus == "WAITING") {
      if (a.actionType == "pick" || a.actionType == "drop") {
        s->actionStatus = "RUNNING";
        running_.emplace_back(a.actionId, now_s + config_.actionDuration);
      } else {
        s->actionStatus = "FAILED";
        s->resultDescription = "action '" + a.actionType + "' is not supported";
      }
    }
  }
}

VehicleCommand Vda5050Vehicle::step(double now_s, const Pose2& pose, bool person_in_field,
                                    bool person_in_warning_field) {
  const double moved = std::hypot(pose.x - pose_.x, pose.y - pose_.y);
  distance_since_node_ += moved;
  measured_speed_ = last_step_s_ >= 0.0 && now_s > last_step_s_ ? moved / (now_s - last_step_s_) : 0.0;
  last_step_s_ = now_s;
  pose_ = pose;
  for (auto it = running_.begin(); it != running_.end();) {
    if (now_s >= it->second) {
      if (auto* s = actionState(it->first)) {
        s->actionStatus = "FINISHED";
      }
      it = running_.erase(it);
      event();
    } else {
      ++it;
    }
  }
  if (field_violation_ != person_in_field) {
    field_violation_ = person_in_field;
    event();
  }
  VehicleCommand cmd;
  const bool can_drive = order_ && operating_mode_ == "AUTOMATIC" && !paused_ && running_.empty();
  while (can_drive && next_ < order_->nodes.size() && order_->nodes[next_].released) {
    const auto& n = order_->nodes[next_];
    if (!n.nodePosition) {
      reachNode(now_s);  // a node without a position is a logical one: nothing to drive to
      continue;
    }
    // The node to stop on is approached slowly and reached closely: stops are at docks and parking
    // places next to shelves, where braking late from speed ran the vehicle into the shelf.
    const bool last = next_ + 1 >= order_->nodes.size() || !order_->nodes[next_ + 1].released;
    // So is a node where the way turns: the vehicle turns there on the spot, and one that reached
    // it at speed slid on past it (0.1-0.2 m into a parking place's back wall when the base
    // turned back out of the place, 2026-11-26).
    bool corner = false;
    bool gentle = false;
    if (!last && order_->nodes[next_ + 1].nodePosition) {
      const auto& m = *order_->nodes[next_ + 1].nodePosition;
      // The way in: from the node before (the pose's bearing swings as the vehicle nears the node).
      Vec2 from{pose.x, pose.y};
      if (next_ > 0 && order_->nodes[next_ - 1].nodePosition)
        from = {order_->nodes[next_ - 1].nodePosition->x, order_->nodes[next_ - 1].nodePosition->y};
      const double in = std::atan2(n.nodePosition->y - from.y, n.nodePosition->x - from.x);
      const double out = std::atan2(m.y - n.nodePosition->y, m.x - n.nodePosition->x);
      const double bend = std::abs(angleDiff(out, in));
      corner = bend > 0.1;
      // The lattice's straight-to-diagonal bends (45°) are driven through at the corner speed:
      // stopping at each held the vehicle to ~0.2 m/s on a lattice route.
      gentle = corner && bend <= kGentleBend;
    }
    const bool stop_here = last || (corner && !gentle);
    const double tol = stop_here || gentle ? std::min(config_.nodeTolerance, 0.1)
                                           : std::max(config_.nodeTolerance,
                                                      n.nodePosition->allowedDeviationXY.value_or(0.0));
    const double dx = n.nodePosition->x - pose.x;
    const double dy = n.nodePosition->y - pose.y;
    const double dist = std::hypot(dx, dy);
    if (dist <= tol) {
      reachNode(now_s);
      if (!running_.empty()) {
        break;  // HARD actions (pick, drop) at the node: stand still until they finish
      }
      continue;
    }
    // Steer for a point a little ahead on the edge into the node, not for the node itself: out of
    // A bend driven through, the vehicle is off the line, and steering for the node swung it to
    // and fro across the edge.
    Vec2 aim{n.nodePosition->x, n.nodePosition->y};
    if (next_ > 0 && order_->nodes[next_ - 1].nodePosition) {
      const Vec2 a{order_->nodes[next_ - 1].nodePosition->x, order_->nodes[next_ - 1].nodePosition->y};
      const Vec2 ab = aim - a;
      const double len = ab.norm();
      if (len > 1e-6) {
        const double along = std::clamp((Vec2{pose.x, pose.y} - a).dot(ab) / len, 0.0, len) + kLookahead;
        if (along < len) {
          aim = a + ab * (along / len);
        }
      }
    }
    const double err = angleDiff(std::atan2(aim.y - pose.y, aim.x - pose.x), pose.theta);
    double vmax = config_.maxSpeed;
    if (next_ > 0 && next_ - 1 < order_->edges.size() && order_->edges[next_ - 1].maxSpeed) {
      vmax = std::min(vmax, *order_->edges[next_ - 1].maxSpeed);
    }
    if (stop_here) {
      vmax = std::min(vmax, 0.05 + 0.6 * dist);
    } else if (gentle) {
      // Braking at half the factsheet's 1 m/s² reaches the node at the corner speed.
      vmax = std::min(vmax, std::sqrt(kCornerSpeed * kCornerSpeed + 2.0 * 0.5 * dist));
    }
    // Turn on the spot, then drive straight: the roadmap's edges are straight and keep clear of
    // shelves only along them (driving while turning cut corners into shelves, 2026-11-26). A
    // vehicle already moving out of a gentle bend turns at the corner speed instead: it began the
    // turn on the node, so it swings a few centimetres outward, never across the inside.
    cmd.w = std::clamp(2.0 * err, -config_.maxTurnRate, config_.maxTurnRate);
    if (std::abs(err) <= 0.1) {
      cmd.v = vmax;
    } else if (std::abs(err) <= kGentleBend + 0.1 && measured_speed_ > 0.5 * kCornerSpeed) {
      // Speed comes back as the heading nears the line.
      const double aligned = std::clamp(1.0 - (std::abs(err) - 0.1) / 0.3, 0.0, 1.0);
      cmd.v = std::min(vmax, kCornerSpeed + (vmax - kCornerSpeed) * aligned);
    } else {
      cmd.v = 0.0;
    }
    break;
  }
  const bool at_base_end = order_ && next_ < order_->nodes.size() && !order_->nodes[next_].released;
  if (at_base_end && !waiting_for_base_) {
    ++starved_stops_;
    event();
  }
  waiting_for_base_ = at_base_end;
  if (motion_pending_ && (std::abs(cmd.v) > 1e-3 || std::abs(cmd.w) > 1e-3)) {
    motion_started_ = std::exchange(motion_pending_, std::nullopt);
  }
  if (person_in_field) {
    // It stops driving. Standing, it may still turn on the spot: its body is a disc, so turning
    // brings it no nearer anyone, and a vehicle that could not turn stood for good beside a
    // neighbour parked diagonally ahead of it on its way into its own parking place (mixed-fleet
    // runs: 5-8 minutes in most seeds).
    cmd.v = 0.0;
    if (measured_speed_ > kStandingSpeed) {
      cmd.w = 0.0;
    }
  } else if (person_in_warning_field) {
    cmd.v = std::clamp(cmd.v, -config_.warningSpeed, config_.warningSpeed);
  }
  const bool driving = std::abs(cmd.v) > 1e-3 || std::abs(cmd.w) > 1e-3;
  if (driving != driving_) {
    driving_ = driving;
    event();
  }
  last_command_ = cmd;
  return cmd;
}

bool Vda5050Vehicle::stateDue(double now_s) const {
  return event_ || now_s - last_state_s_ >= config_.stateInterval;
}

State Vda5050Vehicle::takeState(double now_s, std::int64_t stamp_ns) {
  last_state_s_ = now_s;
  event_ = false;
  State s;
  s.header = {header_id_++, isoTimestamp(stamp_ns), kVersion, config_.manufacturer, config_.serial};
  if (order_) {
    s.orderId = order_->orderId;
    s.orderUpdateId = order_->orderUpdateId;
    for (std::size_t i = next_; i < order_->nodes.size(); ++i) {
      const auto& n = order_->nodes[i];
      s.nodeStates.push_back({n.nodeId, n.sequenceId, n.released, n.nodePosition});
    }
    // Edges still ahead: those after the last node of this order the vehicle passed.
    const std::uint32_t passed = next_ > 0 ? order_->nodes[next_ - 1].sequenceId : 0U;
    for (const auto& e : order_->edges) {
      if (next_ == 0 || e.sequenceId > passed) {
        s.edgeStates.push_back({e.edgeId, e.sequenceId, e.released});
      }
    }
  }
  s.lastNodeId = last_node_id_;
  s.lastNodeSequenceId = last_node_seq_;
  s.driving = driving_;
  s.paused = paused_;
  s.newBaseRequest = waiting_for_base_;
  s.distanceSinceLastNode = distance_since_node_;
  s.operatingMode = operating_mode_;
  s.agvPosition = AgvPosition{pose_.x, pose_.y, pose_.theta, config_.mapId, true};
  s.velocity = Velocity{last_command_.v, 0.0, last_command_.w};
  s.actionStates = action_states_;
  s.batteryState = {battery_ * 100.0, charging_};
  s.errors = errors_;
  s.safetyState = {"NONE", field_violation_};
  return s;
}

bool Vda5050Vehicle::takeFactsheetRequest() {
  return std::exchange(factsheet_requested_, false);
}

Factsheet Vda5050Vehicle::factsheet(std::int64_t stamp_ns) const {
  Factsheet f;
  f.header = {0, isoTimestamp(stamp_ns), kVersion, config_.manufacturer, config_.serial};
  f.seriesName = "fleet-sim VDA 5050 vehicle";
  f.localizationTypes = {"NATURAL"};
  f.navigationTypes = {"VIRTUAL_LINE_GUIDED"};
  f.maxLoadMass = 100.0;
  f.speedMin = 0.0;
  f.speedMax = config_.maxSpeed;
  f.accelerationMax = 1.0;
  f.decelerationMax = 3.0;
  f.heightMax = 0.4;
  f.width = config_.width;
  f.length = config_.length;
  f.minOrderInterval = 0.1;
  f.minStateInterval = 0.1;
  f.defaultStateInterval = config_.stateInterval;
  // Its body is a disc (the simulated world's robots are): the envelope is that disc, as 16 points
  // on its rim, so the master control sees a footprint of its radius, not the square's diagonal.
  const double r = std::max(config_.width, config_.length) / 2.0;
  Envelope2d outline{"default", {}};
  for (int k = 0; k < 16; ++k) {
    const double a = 2.0 * kPi * k / 16.0;
    outline.points.emplace_back(r * std::cos(a), r * std::sin(a));
  }
  f.envelopes2d = {std::move(outline)};
  f.agvActions = {"pick",          "drop",         "startPause",       "stopPause",   "cancelOrder",
                  "startCharging", "stopCharging", "factsheetRequest", "stateRequest"};
  return f;
}

void Vda5050Vehicle::setOperatingMode(std::string mode) {
  if (mode != operating_mode_) {
    operating_mode_ = std::move(mode);
    event();
  }
}

namespace {

/// Whether a disc at (px, py) reaches into the rectangle ahead of a vehicle at `pose` from its
/// centre to `reach` beyond its front, `halfWidth` each side.
bool inFieldAhead(const Pose2& pose, double px, double py, double radius, double front, double reach,
                  double halfWidth) {
  const double c = std::cos(pose.theta);
  const double s = std::sin(pose.theta);
  const double ahead = c * (px - pose.x) + s * (py - pose.y);
  const double side = -s * (px - pose.x) + c * (py - pose.y);
  return ahead + radius >= 0.0 && ahead - radius <= front + reach && std::abs(side) - radius <= halfWidth;
}

}  // namespace

bool Vda5050Vehicle::inProtectiveField(const Pose2& pose, double px, double py, double radius) const {
  const double v = fieldSpeed();
  const double braking = v * v / (2.0 * std::max(config_.brakeDecel, 1e-3));
  // Wider too with speed: a person walking in from the side at an angle reached a vehicle that
  // braked from 1 m/s once it saw them 0.5 m off its side (a 2 cm contact, mixed fleet).
  return inFieldAhead(pose, px, py, radius, config_.length / 2.0, config_.protectiveField + braking,
                      config_.width / 2.0 + config_.fieldSideMargin + braking);
}

bool Vda5050Vehicle::inWarningField(const Pose2& pose, double px, double py, double radius) const {
  const double v = fieldSpeed();
  const double a = std::max(config_.brakeDecel, 1e-3);
  const double braking = v * v / (2.0 * a);
  // It holds the protective field: as wide, longer by the way an approaching person covers while
  // The vehicle brakes.
  const double reach = config_.protectiveField + braking + config_.personApproachSpeed * v / a;
  return inFieldAhead(pose, px, py, radius, config_.length / 2.0, reach,
                      config_.width / 2.0 + config_.fieldSideMargin + braking);
}

bool Vda5050Vehicle::machineInField(const Pose2& pose, double px, double py, double radius) const {
  const double v = fieldSpeed();
  const double reach = kMachineFieldM + v * v / (2.0 * std::max(config_.brakeDecel, 1e-3));
  return inFieldAhead(pose, px, py, radius, config_.length / 2.0, reach, config_.width / 2.0 + kMachineSideM);
}

}  // namespace fleet::sim
