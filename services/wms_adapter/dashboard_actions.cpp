// The dashboard's robot buttons: pause and resume (hold), and send to a charger or home.

#include "dashboard.hpp"

#include <chrono>
#include <limits>
#include <optional>
#include <string>

#include "dashboard_problem.hpp"
#include "fleet/core/bounded_json.hpp"
#include "fleet/core/ids.hpp"
#include "fleet/fleet/task.hpp"
#include "fleet/fleet/task_wire.hpp"
#include "json_reply.hpp"

namespace fleet::wms {

using dashboard_detail::invalidField;
using dashboard_detail::problem;
using nlohmann::json;

namespace {

/// The station of `kind` nearest to `p` in a straight line, or nothing.
const Station* nearest(const StationMap& stations, StationKind kind, Vec2 p) {
  const Station* best = nullptr;
  double bestD = std::numeric_limits<double>::infinity();
  for (const Station* s : stations.ofKind(kind)) {
    const double d = distance(s->pose.position(), p);
    if (d < bestD) {
      bestD = d;
      best = s;
    }
  }
  return best;
}

}  // namespace
void Dashboard::robotAction(const Request& req, Response& res, const std::string& action) {
  const std::string id = req.matches[1];
  res.audit = json{{"robot", id}, {"action", action}}.dump(-1, ' ', false, json::error_handler_t::replace);
  if (!isValidId(id)) {
    replyJson(res, 400, invalidField("id", "not a valid robot id (1-63 characters of A-Z a-z 0-9 _ . : -)"));
    return;
  }
  std::optional<msg::RobotState> robot;
  for (auto& r : d_.view.robots()) {
    if (r.robot_id == id) {
      robot = r;
    }
  }
  if (!robot) {
    replyJson(res, 404, problem("not_found", "no robot with id \"" + id + "\""));
    return;
  }
  if (!d_.gateway.managerOnline()) {
    res.set_header("Retry-After", "2");
    replyJson(res, 503, problem("unavailable", "the fleet manager is unreachable; nothing was sent"));
    return;
  }
  if (action == "pause" || action == "resume") {
    hold(id, action == "pause", res);
  } else {
    sendTo(*robot, action, req, res);
  }
}

void Dashboard::hold(const std::string& robot, bool held, Response& res) {
  msg::Task m;
  m.task_id = robot;
  m.robot = robot;
  m.request_id = d_.requestId();
  m.control = held ? msg::TaskControl::HoldRobot : msg::TaskControl::ReleaseRobot;
  const auto a = d_.gateway.submit({m}, std::chrono::milliseconds(d_.ackTimeoutMs))[0];
  if (!a) {
    res.set_header("Retry-After", "2");
    replyJson(
        res, 503,
        problem("unavailable", "the fleet manager did not acknowledge in time; retry (it is idempotent)"));
  } else if (a->result == msg::AckResult::Stored) {
    replyJson(res, 200, {{"robot", robot}, {"paused", held}, {"task", a->detail}});
  } else if (a->result == msg::AckResult::NotFound) {
    replyJson(res, 404, problem("not_found", "the fleet manager knows no robot \"" + robot + "\""));
  } else {
    replyJson(res, 409, problem("conflict", a->detail));
  }
}

void Dashboard::sendTo(const msg::RobotState& robot, const std::string& action, const Request& req,
                       Response& res) {
  const bool home = action == "home";
  std::string station;
  if (!req.body.empty()) {
    const auto parsed = parseBoundedJson(req.body, {.maxBytes = 4096, .maxDepth = 4, .maxElements = 64});
    const json body = parsed ? *parsed : json();
    if (!body.is_object() || (body.contains("station") && !body["station"].is_string())) {
      replyJson(res, 400,
                invalidField("station", "expected a JSON object with an optional string \"station\""));
      return;
    }
    station = body.value("station", "");
  }
  if (station.empty() && home) {
    std::lock_guard lock(siteMutex_);
    const auto it = homes_.find(robot.robot_id);
    station = it != homes_.end() ? it->second : "";
  }
  if (station.empty()) {
    const Station* s =
        nearest(d_.stations, home ? StationKind::Parking : StationKind::Charging, robot.pose.position());
    if (s == nullptr) {
      replyJson(res, 409,
                problem("conflict",
                        std::string("the site has no ") + (home ? "parking" : "charging") + " station"));
      return;
    }
    station = s->name;
  }
  const std::int64_t now = d_.clock.nowNs();
  const std::string id = action + "-" + robot.robot_id + "-" + std::to_string(now / 1'000'000);
  const json taskJson = {{"id", id},
                         {"kind", home ? "park" : "charge"},
                         {"station", station},
                         {"robot", robot.robot_id},
                         {"priority", 100}};
  auto task = parseTask(taskJson, &d_.stations);
  if (!task) {
    json fields = json::array();
    for (const auto& f : task.error().fields) {
      fields.push_back({{"path", f.path}, {"reason", f.reason}});
    }
    replyJson(res, 400, {{"error", "invalid"}, {"message", task.error().message}, {"fields", fields}});
    return;
  }
  const auto a = d_.gateway.submit({fleet::toWire(*task, d_.requestId(), now)},
                                   std::chrono::milliseconds(d_.ackTimeoutMs))[0];
  if (!a) {
    replyJson(res, 503, problem("unavailable", "the fleet manager did not acknowledge the task in time"));
    return;
  }
  if (a->result != msg::AckResult::Stored && a->result != msg::AckResult::Duplicate) {
    replyJson(res, a->result == msg::AckResult::Invalid ? 400 : 409, problem("refused", a->detail));
    return;
  }
  d_.view.onAccepted(id, toJson(*task).dump(), a->state, now);
  replyJson(
      res, 201,
      {{"robot", robot.robot_id}, {"task", id}, {"station", station}, {"state", msg::toString(a->state)}});
}

}  // namespace fleet::wms
