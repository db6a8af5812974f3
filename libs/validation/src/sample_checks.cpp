#include "fleet/validation/sample_checks.hpp"

#include <cmath>
#include <string>

#include "fleet/core/ids.hpp"
#include "fleet/validation/utf8.hpp"

namespace fleet::validation {
namespace {

/// One check run over a sample: the first problem found wins.
class Checker {
 public:
  explicit Checker(const char* topic) : topic_(topic) {}

  Checker& id(const std::string& v, const char* field) {
    if (!r_ && !isValidId(v)) {
      fail("id", std::string(field) + " is not a valid id (1..63 of [A-Za-z0-9_.:-])");
    }
    return *this;
  }
  Checker& optionalId(const std::string& v, const char* field) { return v.empty() ? *this : id(v, field); }
  Checker& text(const std::string& v, const char* field) {
    if (!r_ && !isValidUtf8(v)) {
      fail("utf8", std::string(field) + " is not valid UTF-8");
    }
    return *this;
  }
  Checker& finite(double v, const char* field) {
    if (!r_ && !std::isfinite(v)) {
      fail("non_finite", std::string(field) + " is not finite");
    }
    return *this;
  }
  Checker& within(double v, double lo, double hi, const char* field) {
    finite(v, field);
    if (!r_ && (v < lo || v > hi)) {
      fail("implausible", std::string(field) + " = " + std::to_string(v) + " outside [" + std::to_string(lo) +
                              ", " + std::to_string(hi) + "]");
    }
    return *this;
  }
  Checker& position(double x, double y, const char* field) {
    within(x, -kMaxCoordinate, kMaxCoordinate, field);
    return within(y, -kMaxCoordinate, kMaxCoordinate, field);
  }
  // The wire's float fields, widened on purpose (clang's -Wdouble-promotion names every implicit one).
  Checker& finite(float v, const char* field) { return finite(static_cast<double>(v), field); }
  Checker& within(float v, double lo, double hi, const char* field) {
    return within(static_cast<double>(v), lo, hi, field);
  }
  Checker& position(float x, float y, const char* field) {
    return position(static_cast<double>(x), static_cast<double>(y), field);
  }
  Checker& pose(const Pose2& p, const char* field) {
    position(p.x, p.y, field);
    return finite(p.theta, field);
  }
  template <class E>
  Checker& known(E v, E last, const char* field) {
    if (!r_ && static_cast<int>(v) > static_cast<int>(last)) {
      fail("enum",
           std::string(field) + " = " + std::to_string(static_cast<int>(v)) + " is not a known value");
    }
    return *this;
  }
  Checker& size(std::size_t n, std::size_t bound, const char* field) {
    if (!r_ && n > bound) {
      fail("too_large", std::string(field) + " has " + std::to_string(n) + " elements, at most " +
                            std::to_string(bound) + " allowed");
    }
    return *this;
  }
  Checker& require(bool ok, const char* reason, const std::string& detail) {
    if (!r_ && !ok) {
      fail(reason, detail);
    }
    return *this;
  }
  [[nodiscard]] bool failed() const { return r_.has_value(); }
  std::optional<Rejection> done() { return std::move(r_); }

 private:
  void fail(const char* reason, std::string detail) { r_ = Rejection{topic_, reason, std::move(detail)}; }
  const char* topic_;
  std::optional<Rejection> r_;
};

bool repair(std::string& s) {
  if (isValidUtf8(s)) {
    return false;
  }
  s = repairUtf8(s);
  return true;
}

}  // namespace

const char* topicOf(const msg::TaskStatus&) {
  return "TaskStatus";
}
const char* topicOf(const msg::TaskEvent&) {
  return "TaskEvent";
}
const char* topicOf(const msg::TaskAck&) {
  return "TaskAck";
}

bool repairText(msg::TaskStatus& m) {
  return repair(m.error);
}
bool repairText(msg::TaskEvent& m) {
  return repair(m.reason);
}
bool repairText(msg::TaskAck& m) {
  return repair(m.detail);
}

std::optional<Rejection> check(const msg::Task& m) {
  // The fields of the task itself are the dispatcher's to judge (it answers with field errors).
  Checker c("Task");
  c.id(m.task_id, "task_id").id(m.request_id, "request_id");
  c.known(m.kind, msg::TaskKind::Multistop, "kind").known(m.control, msg::TaskControl::Change, "control");
  c.text(m.pickup, "pickup").text(m.dropoff, "dropoff").text(m.station, "station").text(m.robot, "robot");
  c.size(m.steps.size(), 16, "steps");
  for (const auto& st : m.steps) {
    c.known(st.action, msg::StepAction::Charge, "steps[].action");
    c.text(st.station, "steps[].station").text(st.load_id, "steps[].load_id");
  }
  return c.done();
}

std::optional<Rejection> check(const msg::TaskAck& m) {
  Checker c("TaskAck");
  c.id(m.request_id, "request_id").optionalId(m.task_id, "task_id");
  c.known(m.result, msg::AckResult::Unavailable, "result").known(m.state, msg::TaskState::Rejected, "state");
  return c.text(m.detail, "detail").done();
}

std::optional<Rejection> check(const msg::TaskEvent& m) {
  Checker c("TaskEvent");
  c.id(m.task_id, "task_id").optionalId(m.robot_id, "robot_id").optionalId(m.station, "station");
  c.known(m.state, msg::TaskState::Rejected, "state");
  return c.text(m.reason, "reason").done();
}

std::optional<Rejection> check(const msg::TaskAssignment& m) {
  Checker c("TaskAssignment");
  c.id(m.robot_id, "robot_id").optionalId(m.task_id, "task_id");
  // A task is somewhere to go; no task is nowhere to go.
  c.require(m.task_id.empty() || !m.goals.empty(), "structure", "task \"" + m.task_id + "\" has no goals");
  c.require(!m.task_id.empty() || m.goals.empty(), "structure", "goals without a task id");
  c.size(m.goals.size(), 16, "goals");
  for (const auto& g : m.goals) {
    c.pose(g.pose, "goals[].pose").optionalId(g.station, "goals[].station");
    c.known(g.action, msg::GoalAction::Park, "goals[].action");
    c.within(g.duration_s, 0.0, kMaxDwellS, "goals[].duration_s");
    c.optionalId(g.load_id, "goals[].load_id");
  }
  return c.done();
}

std::optional<Rejection> check(const msg::TaskStatus& m) {
  Checker c("TaskStatus");
  c.id(m.robot_id, "robot_id").optionalId(m.task_id, "task_id");
  c.known(m.state, msg::TaskState::Rejected, "state");
  c.within(m.progress, 0.0, 1.0, "progress");
  return c.text(m.error, "error").done();
}

std::optional<Rejection> check(const msg::RobotState& m) {
  Checker c("RobotState");
  c.id(m.robot_id, "robot_id").optionalId(m.task_id, "task_id").pose(m.pose, "pose");
  for (double v : m.covariance) {
    c.finite(v, "covariance");
  }
  c.within(m.v, -kMaxSpeed, kMaxSpeed, "v").within(m.w, -kMaxSpeed, kMaxSpeed, "w");
  c.within(m.battery, 0.0, 1.0, "battery").within(m.radius, 0.0, kMaxRadius, "radius");
  c.known(m.activity, msg::RobotActivity::Faulted, "activity");
  return c.known(m.mode, msg::RobotMode::Fault, "mode").done();
}

std::optional<Rejection> check(const msg::PredictedDiscs& m) {
  Checker c("PredictedDiscs");
  c.id(m.source_id, "source_id").known(m.kind, msg::SourceKind::Human, "kind");
  c.within(m.dt, 0.0, 3600.0, "dt").require(m.dt > 0.0F, "implausible", "dt must be > 0");
  c.size(m.discs.size(), 64, "discs");
  for (const auto& d : m.discs) {
    c.position(d.x, d.y, "discs[]").within(d.r, 0.0, kMaxRadius, "discs[].r");
    c.within(d.sigma, 0.0, kMaxCoordinate, "discs[].sigma");
    c.finite(d.cov_xx, "discs[].cov_xx")
        .finite(d.cov_xy, "discs[].cov_xy")
        .finite(d.cov_yy, "discs[].cov_yy");
  }
  return c.done();
}

std::optional<Rejection> check(const msg::PeopleSeen& m) {
  Checker c("PeopleSeen");
  c.id(m.robot_id, "robot_id").size(m.people.size(), msg::kMaxPeopleSeen, "people");
  for (const auto& p : m.people) {
    c.position(p.x, p.y, "people[]").within(p.r, 0.0, kMaxRadius, "people[].r");
    c.within(p.vx, -kMaxSpeed, kMaxSpeed, "people[].vx").within(p.vy, -kMaxSpeed, kMaxSpeed, "people[].vy");
    c.require(p.r > 0.0F, "implausible", "people[].r must be > 0");
  }
  return c.done();
}

std::optional<Rejection> check(const msg::RiskMap& m) {
  Checker c("RiskMap");
  c.position(m.origin_x, m.origin_y, "origin").within(m.resolution, 1e-6, 1e3, "resolution");
  const std::size_t cells = static_cast<std::size_t>(m.width) * static_cast<std::size_t>(m.height);
  c.require(m.width > 0 && m.height > 0 && cells <= kMaxRiskCells, "too_large",
            "width x height = " + std::to_string(m.width) + " x " + std::to_string(m.height) +
                " must be 1 .. 2^26 cells");
  c.require(m.levels >= 1, "implausible", "levels must be >= 1");
  c.finite(m.horizon_s, "horizon_s").finite(m.scene_index, "scene_index");
  c.size(m.runs.size(), std::min(kMaxRiskRuns, cells), "runs")
      .size(m.regions.size(), kMaxRiskRegions, "regions");
  for (const auto& r : m.regions) {
    c.size(r.outer.size(), kMaxRingPoints, "regions[].outer")
        .size(r.holes.size(), kMaxRingHoles, "regions[].holes");
    for (const auto& h : r.holes) {
      c.size(h.size(), kMaxRingPoints, "regions[].holes[]");
    }
  }
  return c.done();
}

std::optional<Rejection> check(const msg::SensorFrame& m) {
  Checker c("SensorFrame");
  c.id(m.robot_id, "robot_id");
  c.within(m.ds_left, -kMaxWheelStep, kMaxWheelStep, "ds_left");
  c.within(m.ds_right, -kMaxWheelStep, kMaxWheelStep, "ds_right");
  if (m.wheel_totals_valid) {
    c.within(m.wheel_left_total, -kMaxWheelTotal, kMaxWheelTotal, "wheel_left_total");
    c.within(m.wheel_right_total, -kMaxWheelTotal, kMaxWheelTotal, "wheel_right_total");
  }
  c.finite(m.angle_min, "angle_min").finite(m.angle_increment, "angle_increment");
  c.within(m.range_max, 0.0, 1e4, "range_max");
  c.size(m.ranges.size(), 1024, "ranges");
  if (m.compass_valid) {
    c.finite(m.compass, "compass");
  }
  c.size(m.landmarks.size(), 64, "landmarks");
  for (const auto& l : m.landmarks) {
    c.finite(l.bearing, "landmarks[].bearing");
  }
  c.size(m.detections.size(), 256, "detections");
  for (const auto& d : m.detections) {
    c.position(d.x, d.y, "detections[]").within(d.r, 0.0, kMaxRadius, "detections[].r");
    c.known(d.kind, msg::SourceKind::Human, "detections[].kind");
  }
  return c.within(m.battery, 0.0, 1.0, "battery").done();
}

std::optional<Rejection> check(const msg::VelocityCommand& m) {
  Checker c("VelocityCommand");
  c.id(m.robot_id, "robot_id");
  return c.within(m.v, -kMaxSpeed, kMaxSpeed, "v").within(m.w, -kMaxSpeed, kMaxSpeed, "w").done();
}

std::optional<Rejection> check(const msg::GroundTruth& m) {
  Checker c("GroundTruth");
  c.size(m.bodies.size(), kMaxBodies, "bodies").size(m.contacts.size(), kMaxContacts, "contacts");
  for (const auto& b : m.bodies) {
    c.id(b.id, "bodies[].id").pose(b.pose, "bodies[].pose");
    c.within(b.v, -kMaxSpeed, kMaxSpeed, "bodies[].v").within(b.radius, 0.0, kMaxRadius, "bodies[].radius");
  }
  for (const auto& k : m.contacts) {
    c.finite(k.depth, "contacts[].depth");
  }
  return c.done();
}

std::optional<Rejection> check(const msg::TrafficRelease& m) {
  Checker c("TrafficRelease");
  c.id(m.robot_id, "robot_id").size(m.base.size(), 64, "base").size(m.horizon.size(), 32, "horizon");
  for (const auto* seq : {&m.base, &m.horizon}) {
    for (const auto& n : *seq) {
      c.position(n.x, n.y, "node").require(n.node >= 0, "implausible", "a released node id is negative");
    }
  }
  return c.done();
}

std::optional<Rejection> check(const msg::TrafficProgress& m) {
  Checker c("TrafficProgress");
  c.id(m.robot_id, "robot_id").pose(m.pose, "pose").optionalId(m.goal_station, "goal_station");
  if (m.has_goal) {
    c.pose(m.goal, "goal");
  }
  return c.require(m.node >= -1, "implausible", "node must be >= -1").done();
}

std::optional<Rejection> check(const msg::TrafficClosure& m) {
  Checker c("TrafficClosure");
  c.id(m.closure_id, "closure_id").text(m.reason, "reason");
  c.size(m.area.size(), 256, "area").size(m.nodes.size(), 4096, "nodes").size(m.lanes.size(), 4096, "lanes");
  for (const auto& p : m.area) {
    c.position(p.x, p.y, "area[]");
  }
  c.require(m.area.empty() || m.area.size() >= 3, "structure", "area needs at least 3 corners (or none)");
  for (const auto v : m.nodes) {
    c.require(v >= 0, "implausible", "a node id is negative");
  }
  for (const auto& e : m.lanes) {
    c.require(e.from >= 0 && e.to >= 0, "implausible", "a lane's node id is negative");
  }
  // A reopening names only the id; a closure must close something.
  return c
      .require(!m.active || !m.area.empty() || !m.nodes.empty() || !m.lanes.empty(), "structure",
               "an active closure needs an area, nodes or lanes")
      .done();
}

std::optional<Rejection> check(const msg::Roadmap& m) {
  Checker c("Roadmap");
  c.size(m.nodes.size(), kMaxRoadmapNodes, "nodes").size(m.edges.size(), kMaxRoadmapEdges, "edges");
  c.require(m.kinds.size() == m.nodes.size() && m.open.size() == m.nodes.size(), "structure",
            "kinds and open must have one entry per node");
  // Edges and releases name nodes by id, and readers look a node up by its index.
  for (std::size_t i = 0; i < m.nodes.size(); ++i) {
    c.position(m.nodes[i].x, m.nodes[i].y, "nodes[]");
    if (m.nodes[i].node != static_cast<std::int32_t>(i)) {
      c.require(
          false, "structure",
          "nodes[" + std::to_string(i) + "] has id " + std::to_string(m.nodes[i].node) + ", not its index");
    }
  }
  for (const auto k : m.kinds) {
    if (k > kMaxRoadmapNodeKind) {
      c.require(false, "enum", "kinds[] = " + std::to_string(k) + " is not a known node kind (0..5)");
    }
  }
  const auto count = static_cast<std::int64_t>(m.nodes.size());
  for (const auto& e : m.edges) {
    if (!(e.from >= 0 && e.from < count && e.to >= 0 && e.to < count)) {
      c.require(false, "structure",
                "edge " + std::to_string(e.from) + " -> " + std::to_string(e.to) + " names an unknown node");
    }
    c.within(e.duration_s, 0.0, 1e6, "edges[].duration_s");
  }
  return c.done();
}

}  // namespace fleet::validation
