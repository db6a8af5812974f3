// Copies between the C++ messages and the idlc-generated C structs (the task messages in
// convert_tasks.cpp). Writing never truncates: a string or sequence over its IDL bound is a
// MessageError naming the field.

#include <cstring>
#include <string>
#include <type_traits>

#include "convert_detail.hpp"

namespace fleet::transport {
using namespace convert_detail;  // the helpers this file shares with the other conversions

// ---- RobotState
// fleet_Matrix3 is nine doubles in row-major order (idl/fleet.idl says why it is not an array).
static_assert(sizeof(fleet_Matrix3) == sizeof(std::array<double, 9>));
void Traits<msg::RobotState>::toC(const msg::RobotState& in, C& out, Arena&) {
  putStr(out.robot_id, in.robot_id, "RobotState.robot_id");
  out.stamp_ns = in.stamp_ns;
  out.pose = putPose(in.pose);
  std::memcpy(&out.covariance, in.covariance.data(), sizeof(out.covariance));
  out.v = in.v;
  out.w = in.w;
  out.mode = static_cast<fleet_RobotMode>(in.mode);
  out.battery = in.battery;
  putStr(out.task_id, in.task_id, "RobotState.task_id");
  out.radius = in.radius;
  out.paused = in.paused;
  out.activity = static_cast<fleet_RobotActivity>(in.activity);
}
msg::RobotState Traits<msg::RobotState>::fromC(const C& in) {
  msg::RobotState m;
  m.robot_id = getStr(in.robot_id);
  m.stamp_ns = in.stamp_ns;
  m.pose = getPose(in.pose);
  std::memcpy(m.covariance.data(), &in.covariance, sizeof(in.covariance));
  m.v = in.v;
  m.w = in.w;
  m.mode = getEnum(in.mode, msg::RobotMode::Fault);
  m.battery = in.battery;
  m.task_id = getStr(in.task_id);
  m.radius = in.radius;
  m.paused = in.paused;
  // A value from a newer peer is not guessed at: Unset, so the reader derives it from `mode`.
  const auto act = static_cast<int>(in.activity);
  m.activity = act < 0 || act > static_cast<int>(msg::RobotActivity::Faulted)
                   ? msg::RobotActivity::Unset
                   : static_cast<msg::RobotActivity>(act);
  return m;
}

// ---- PeopleSeen
void Traits<msg::PeopleSeen>::toC(const msg::PeopleSeen& in, C& out, Arena& arena) {
  putStr(out.robot_id, in.robot_id, "PeopleSeen.robot_id");
  out.stamp_ns = in.stamp_ns;
  putSeq(out.people, in.people, msg::kMaxPeopleSeen, arena, "PeopleSeen.people",
         [](const msg::SeenPerson& p, fleet_SeenPerson& c) {
           c = {p.x, p.y, p.vx, p.vy, p.r, p.velocity_known};
         });
}
msg::PeopleSeen Traits<msg::PeopleSeen>::fromC(const C& in) {
  msg::PeopleSeen m;
  m.robot_id = getStr(in.robot_id);
  m.stamp_ns = in.stamp_ns;
  m.people = getSeq(in.people, [](const fleet_SeenPerson& c) {
    return msg::SeenPerson{c.x, c.y, c.vx, c.vy, c.r, c.velocity_known};
  });
  return m;
}

// ---- PredictedDiscs
void Traits<msg::PredictedDiscs>::toC(const msg::PredictedDiscs& in, C& out, Arena& arena) {
  putStr(out.source_id, in.source_id, "PredictedDiscs.source_id");
  out.kind = static_cast<fleet_SourceKind>(in.kind);
  out.t0_ns = in.t0_ns;
  out.dt = in.dt;
  putSeq(out.discs, in.discs, 64, arena, "PredictedDiscs.discs", [](const msg::Disc& d, fleet_Disc& c) {
    c = {d.x, d.y, d.r, d.sigma, d.cov_xx, d.cov_xy, d.cov_yy};
  });
}
msg::PredictedDiscs Traits<msg::PredictedDiscs>::fromC(const C& in) {
  msg::PredictedDiscs m;
  m.source_id = getStr(in.source_id);
  m.kind = getEnum(in.kind, msg::SourceKind::Human);
  m.t0_ns = in.t0_ns;
  m.dt = in.dt;
  m.discs = getSeq(in.discs, [](const fleet_Disc& c) {
    return msg::Disc{c.x, c.y, c.r, c.sigma, c.cov_xx, c.cov_xy, c.cov_yy};
  });
  return m;
}

// ---- RiskMap
namespace {
void putRing(const msg::Ring& ring, fleet_Ring& c, Arena& arena, const char* field) {
  putSeq(c.points, ring, 16384, arena, field, [](const Vec2& p, fleet_Point2D& q) { q = {p.x, p.y}; });
}
msg::Ring getRing(const fleet_Ring& c) {
  return getSeq(c.points, [](const fleet_Point2D& q) { return Vec2{q.x, q.y}; });
}
}  // namespace

void Traits<msg::RiskMap>::toC(const msg::RiskMap& in, C& out, Arena& arena) {
  out.stamp_ns = in.stamp_ns;
  out.origin_x = in.origin_x;
  out.origin_y = in.origin_y;
  out.resolution = in.resolution;
  out.width = in.width;
  out.height = in.height;
  out.levels = in.levels;
  out.horizon_s = in.horizon_s;
  out.scene_index = in.scene_index;
  out.sources = in.sources;
  putSeq(out.runs, in.runs, 4194304, arena, "RiskMap.runs", [](const msg::LevelRun& r, fleet_LevelRun& c) {
    c = {r.level, r.count};
  });
  putSeq(out.regions, in.regions, 16384, arena, "RiskMap.regions",
         [&arena](const msg::Region& r, fleet_Region& c) {
           c.level = r.level;
           putRing(r.outer, c.outer, arena, "RiskMap.regions[].outer");
           putSeq(c.holes, r.holes, 256, arena, "RiskMap.regions[].holes",
                  [&arena](const msg::Ring& h, fleet_Ring& hc) {
                    putRing(h, hc, arena, "RiskMap.regions[].holes[]");
                  });
         });
}
msg::RiskMap Traits<msg::RiskMap>::fromC(const C& in) {
  msg::RiskMap m;
  m.stamp_ns = in.stamp_ns;
  m.origin_x = in.origin_x;
  m.origin_y = in.origin_y;
  m.resolution = in.resolution;
  m.width = in.width;
  m.height = in.height;
  m.levels = in.levels;
  m.horizon_s = in.horizon_s;
  m.scene_index = in.scene_index;
  m.sources = in.sources;
  m.runs = getSeq(in.runs, [](const fleet_LevelRun& c) { return msg::LevelRun{c.level, c.count}; });
  m.regions = getSeq(in.regions, [](const fleet_Region& c) {
    return msg::Region{c.level, getRing(c.outer),
                       getSeq(c.holes, [](const fleet_Ring& h) { return getRing(h); })};
  });
  return m;
}

// ---- SensorFrame
void Traits<msg::SensorFrame>::toC(const msg::SensorFrame& in, C& out, Arena& arena) {
  putStr(out.robot_id, in.robot_id, "SensorFrame.robot_id");
  out.stamp_ns = in.stamp_ns;
  out.seq = in.seq;
  out.ds_left = in.ds_left;
  out.ds_right = in.ds_right;
  out.angle_min = in.angle_min;
  out.angle_increment = in.angle_increment;
  out.range_max = in.range_max;
  putSeq(out.ranges, in.ranges, 1024, arena, "SensorFrame.ranges", [](float r, float& c) { c = r; });
  out.compass_valid = in.compass_valid;
  out.compass = in.compass;
  putSeq(out.landmarks, in.landmarks, 64, arena, "SensorFrame.landmarks",
         [](const msg::LandmarkBearing& l, fleet_LandmarkBearing& c) {
           c = {l.id, l.bearing};
         });
  putSeq(out.detections, in.detections, 256, arena, "SensorFrame.detections",
         [](const msg::Detection& d, fleet_Detection& c) {
           c = {static_cast<fleet_SourceKind>(d.kind), d.x, d.y, d.r};
         });
  out.battery = in.battery;
  out.charging = in.charging;
  out.wheel_totals_valid = in.wheel_totals_valid;
  out.wheel_left_total = in.wheel_left_total;
  out.wheel_right_total = in.wheel_right_total;
  out.driver_session = in.driver_session;
}
msg::SensorFrame Traits<msg::SensorFrame>::fromC(const C& in) {
  msg::SensorFrame m;
  m.robot_id = getStr(in.robot_id);
  m.stamp_ns = in.stamp_ns;
  m.seq = in.seq;
  m.ds_left = in.ds_left;
  m.ds_right = in.ds_right;
  m.angle_min = in.angle_min;
  m.angle_increment = in.angle_increment;
  m.range_max = in.range_max;
  m.ranges = getSeq(in.ranges, [](float r) { return r; });
  m.compass_valid = in.compass_valid;
  m.compass = in.compass;
  m.landmarks = getSeq(in.landmarks, [](const fleet_LandmarkBearing& c) {
    return msg::LandmarkBearing{c.id, c.bearing};
  });
  m.detections = getSeq(in.detections, [](const fleet_Detection& c) {
    return msg::Detection{getEnum(c.kind, msg::SourceKind::Human), c.x, c.y, c.r};
  });
  m.battery = in.battery;
  m.charging = in.charging;
  m.wheel_totals_valid = in.wheel_totals_valid;
  m.wheel_left_total = in.wheel_left_total;
  m.wheel_right_total = in.wheel_right_total;
  m.driver_session = in.driver_session;
  return m;
}

// ---- VelocityCommand
void Traits<msg::VelocityCommand>::toC(const msg::VelocityCommand& in, C& out, Arena&) {
  putStr(out.robot_id, in.robot_id, "VelocityCommand.robot_id");
  out.v = in.v;
  out.w = in.w;
  out.stamp_ns = in.stamp_ns;
  out.seq = in.seq;
}
msg::VelocityCommand Traits<msg::VelocityCommand>::fromC(const C& in) {
  return {getStr(in.robot_id), in.v, in.w, in.stamp_ns, in.seq};
}

// ---- Clock / StepDone
void Traits<msg::Clock>::toC(const msg::Clock& in, C& out, Arena&) {
  out = {in.step, in.sim_time_ns, in.dt_ns, in.lockstep};
}
msg::Clock Traits<msg::Clock>::fromC(const C& in) {
  return {in.step, in.sim_time_ns, in.dt_ns, in.lockstep};
}

void Traits<msg::StepDone>::toC(const msg::StepDone& in, C& out, Arena& arena) {
  putStr(out.participant_id, in.participant_id, "StepDone.participant_id");
  out.step = in.step;
  putSeq(out.commands, in.commands, msg::kMaxStepDoneCommands, arena, "StepDone.commands",
         [](const msg::CommandMark& m, fleet_CommandMark& c) {
           putStr(c.robot_id, m.robot_id, "StepDone.commands.robot_id");
           c.seq = m.seq;
         });
}
msg::StepDone Traits<msg::StepDone>::fromC(const C& in) {
  msg::StepDone m;
  m.participant_id = getStr(in.participant_id);
  m.step = in.step;
  m.commands = getSeq(in.commands, [](const fleet_CommandMark& c) {
    return msg::CommandMark{getStr(c.robot_id), c.seq};
  });
  return m;
}

// ---- GroundTruth
void Traits<msg::GroundTruth>::toC(const msg::GroundTruth& in, C& out, Arena& arena) {
  out.step = in.step;
  out.sim_time_ns = in.sim_time_ns;
  putSeq(out.bodies, in.bodies, 65536, arena, "GroundTruth.bodies", [](const msg::Body& b, fleet_Body& c) {
    putStr(c.id, b.id, "GroundTruth.bodies[].id");
    c.kind = static_cast<fleet_SourceKind>(b.kind);
    c.pose = putPose(b.pose);
    c.v = b.v;
    c.radius = b.radius;
  });
  putSeq(out.contacts, in.contacts, 65536, arena, "GroundTruth.contacts",
         [](const msg::Contact& k, fleet_Contact& c) {
           putStr(c.a, k.a, "GroundTruth.contacts[].a");
           putStr(c.b, k.b, "GroundTruth.contacts[].b");
           c.depth = k.depth;
         });
}
msg::GroundTruth Traits<msg::GroundTruth>::fromC(const C& in) {
  msg::GroundTruth m;
  m.step = in.step;
  m.sim_time_ns = in.sim_time_ns;
  m.bodies = getSeq(in.bodies, [](const fleet_Body& c) {
    return msg::Body{getStr(c.id), getEnum(c.kind, msg::SourceKind::Human), getPose(c.pose), c.v, c.radius};
  });
  m.contacts = getSeq(in.contacts, [](const fleet_Contact& c) {
    return msg::Contact{getStr(c.a), getStr(c.b), c.depth};
  });
  return m;
}

// ---- Traffic
namespace {
fleet_RouteNode putNode(const msg::RouteNode& n) {
  return {n.node, n.x, n.y};
}
msg::RouteNode getNode(const fleet_RouteNode& c) {
  return {c.node, c.x, c.y};
}
}  // namespace

void Traits<msg::Roadmap>::toC(const msg::Roadmap& in, C& out, Arena& arena) {
  putStr(out.site, in.site, "Roadmap.site");
  out.epoch = in.epoch;
  out.revision = in.revision;
  if (in.kinds.size() != in.nodes.size() || in.open.size() != in.nodes.size()) {
    throw MessageError("Roadmap: kinds and open must have one entry per node");
  }
  putSeq(out.nodes, in.nodes, 1048576, arena, "Roadmap.nodes",
         [](const msg::RouteNode& n, fleet_RouteNode& c) { c = putNode(n); });
  putSeq(out.kinds, in.kinds, 1048576, arena, "Roadmap.kinds",
         [](std::uint8_t k, std::uint8_t& c) { c = k; });
  putSeq(out.open, in.open, 1048576, arena, "Roadmap.open", [](bool o, bool& c) { c = o; });
  putSeq(out.edges, in.edges, 4194304, arena, "Roadmap.edges",
         [](const msg::RoadmapEdge& e, fleet_RoadmapEdge& c) {
           c = fleet_RoadmapEdge{e.from, e.to, e.duration_s, e.open};
         });
  out.stamp_ns = in.stamp_ns;
  out.robot_radius = static_cast<float>(in.robot_radius);
}
msg::Roadmap Traits<msg::Roadmap>::fromC(const C& in) {
  msg::Roadmap m;
  m.site = getStr(in.site);
  m.epoch = in.epoch;
  m.revision = in.revision;
  m.nodes = getSeq(in.nodes, getNode);
  m.kinds = getSeq(in.kinds, [](std::uint8_t k) { return k; });
  m.open = getSeq(in.open, [](bool o) { return o; });
  m.edges = getSeq(in.edges, [](const fleet_RoadmapEdge& c) {
    return msg::RoadmapEdge{c.from, c.to, c.duration_s, c.open};
  });
  m.stamp_ns = in.stamp_ns;
  m.robot_radius = static_cast<double>(in.robot_radius);
  return m;
}

void Traits<msg::TrafficClosure>::toC(const msg::TrafficClosure& in, C& out, Arena& arena) {
  putStr(out.closure_id, in.closure_id, "TrafficClosure.closure_id");
  out.active = in.active;
  putSeq(out.area, in.area, 256, arena, "TrafficClosure.area", [](const Vec2& p, fleet_Point2D& q) {
    q = {p.x, p.y};
  });
  putSeq(out.nodes, in.nodes, 4096, arena, "TrafficClosure.nodes",
         [](std::int32_t v, std::int32_t& c) { c = v; });
  putSeq(out.lanes, in.lanes, 4096, arena, "TrafficClosure.lanes",
         [](const msg::NodePair& e, fleet_NodePair& c) {
           c = fleet_NodePair{e.from, e.to};
         });
  putStr(out.reason, in.reason, "TrafficClosure.reason");
  out.stamp_ns = in.stamp_ns;
}
msg::TrafficClosure Traits<msg::TrafficClosure>::fromC(const C& in) {
  msg::TrafficClosure m;
  m.closure_id = getStr(in.closure_id);
  m.active = in.active;
  m.area = getSeq(in.area, [](const fleet_Point2D& q) { return Vec2{q.x, q.y}; });
  m.nodes = getSeq(in.nodes, [](std::int32_t v) { return v; });
  m.lanes = getSeq(in.lanes, [](const fleet_NodePair& c) { return msg::NodePair{c.from, c.to}; });
  m.reason = getStr(in.reason);
  m.stamp_ns = in.stamp_ns;
  return m;
}

void Traits<msg::TrafficRelease>::toC(const msg::TrafficRelease& in, C& out, Arena& arena) {
  putStr(out.robot_id, in.robot_id, "TrafficRelease.robot_id");
  out.epoch = in.epoch;
  out.seq = in.seq;
  putSeq(out.base, in.base, 64, arena, "TrafficRelease.base",
         [](const msg::RouteNode& n, fleet_RouteNode& c) { c = putNode(n); });
  putSeq(out.horizon, in.horizon, 32, arena, "TrafficRelease.horizon",
         [](const msg::RouteNode& n, fleet_RouteNode& c) { c = putNode(n); });
  out.ends_at_goal = in.ends_at_goal;
  out.stamp_ns = in.stamp_ns;
}
msg::TrafficRelease Traits<msg::TrafficRelease>::fromC(const C& in) {
  msg::TrafficRelease m;
  m.robot_id = getStr(in.robot_id);
  m.epoch = in.epoch;
  m.seq = in.seq;
  m.base = getSeq(in.base, getNode);
  m.horizon = getSeq(in.horizon, getNode);
  m.ends_at_goal = in.ends_at_goal;
  m.stamp_ns = in.stamp_ns;
  return m;
}

void Traits<msg::TrafficProgress>::toC(const msg::TrafficProgress& in, C& out, Arena&) {
  putStr(out.robot_id, in.robot_id, "TrafficProgress.robot_id");
  out.epoch = in.epoch;
  out.node = in.node;
  out.pose = putPose(in.pose);
  out.has_goal = in.has_goal;
  out.goal = putPose(in.goal);
  putStr(out.goal_station, in.goal_station, "TrafficProgress.goal_station");
  out.priority = in.priority;
  out.holding = in.holding;
  out.blocked = in.blocked;
  out.follows = in.follows;
  out.stamp_ns = in.stamp_ns;
}
msg::TrafficProgress Traits<msg::TrafficProgress>::fromC(const C& in) {
  msg::TrafficProgress m;
  m.robot_id = getStr(in.robot_id);
  m.epoch = in.epoch;
  m.node = in.node;
  m.pose = getPose(in.pose);
  m.has_goal = in.has_goal;
  m.goal = getPose(in.goal);
  m.goal_station = getStr(in.goal_station);
  m.priority = in.priority;
  m.holding = in.holding;
  m.blocked = in.blocked;
  m.follows = in.follows;
  m.stamp_ns = in.stamp_ns;
  return m;
}

}  // namespace fleet::transport
