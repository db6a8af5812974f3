#include "pose_store.hpp"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <system_error>

namespace fleet::agent {

Expected<SavedPoses> readPoseFile(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) {
    return SavedPoses{};
  }
  std::ifstream in(path);
  if (!in) {
    return unexpected("pose_file", "pose file " + path + ": cannot be read");
  }
  const auto j = nlohmann::json::parse(in, nullptr, false);
  if (j.is_discarded()) {
    return unexpected("pose_file", "pose file " + path + ": not JSON");
  }
  if (!j.is_object() || !j.contains("robots") || !j["robots"].is_object()) {
    return unexpected("pose_file", "pose file " + path + ": robots: required object of robot id -> pose");
  }
  SavedPoses out;
  for (const auto& [id, p] : j["robots"].items()) {
    const std::string at = "pose file " + path + ": robots." + id;
    if (!p.is_object()) {
      return unexpected("pose_file", at + ": required object {x, y, theta, saved_unix_ms}");
    }
    SavedPose s;
    for (const auto& [key, value] :
         {std::pair{"x", &s.pose.x}, std::pair{"y", &s.pose.y}, std::pair{"theta", &s.pose.theta}}) {
      if (!p.contains(key) || !p[key].is_number() || !std::isfinite(p[key].get<double>())) {
        return unexpected("pose_file", at + "." + key + ": required finite number");
      }
      *value = p[key].get<double>();
    }
    if (!p.contains("saved_unix_ms") || !p["saved_unix_ms"].is_number_integer()) {
      return unexpected("pose_file", at + ".saved_unix_ms: required integer");
    }
    s.savedUnixMs = p["saved_unix_ms"].get<std::int64_t>();
    const bool left = p.contains("wheel_left_total");
    const bool right = p.contains("wheel_right_total");
    if (left != right) {
      return unexpected("pose_file", at + "." + (left ? "wheel_right_total" : "wheel_left_total") +
                                         ": required with the other wheel's total");
    }
    if (left) {
      WheelTotals w;
      for (const auto& [key, value] :
           {std::pair{"wheel_left_total", &w.left}, std::pair{"wheel_right_total", &w.right}}) {
        if (!p[key].is_number() || !std::isfinite(p[key].get<double>())) {
          return unexpected("pose_file", at + "." + key + ": required finite number");
        }
        *value = p[key].get<double>();
      }
      if (p.contains("driver_session")) {
        if (!p["driver_session"].is_number_unsigned()) {
          return unexpected("pose_file", at + ".driver_session: required non-negative integer");
        }
        w.session = p["driver_session"].get<std::uint64_t>();
      }
      s.wheels = w;
    } else if (p.contains("driver_session")) {
      return unexpected("pose_file", at + ".driver_session: required with the wheel totals");
    }
    out[id] = s;
  }
  return out;
}

Expected<void> writePoseFile(const std::string& path, const SavedPoses& poses) {
  nlohmann::json j;
  j["robots"] = nlohmann::json::object();
  for (const auto& [id, s] : poses) {
    auto& r = j["robots"][id];
    r = {{"x", s.pose.x}, {"y", s.pose.y}, {"theta", s.pose.theta}, {"saved_unix_ms", s.savedUnixMs}};
    if (s.wheels) {
      r["wheel_left_total"] = s.wheels->left;
      r["wheel_right_total"] = s.wheels->right;
      if (s.wheels->session != 0) {
        r["driver_session"] = s.wheels->session;
      }
    }
  }
  const std::string tmp = path + ".tmp";
  {
    std::ofstream out(tmp, std::ios::trunc);
    out << j.dump();
    if (!out.flush()) {
      return unexpected("pose_file", "pose file " + tmp + ": cannot be written");
    }
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) {
    return unexpected("pose_file", "pose file " + path + ": cannot replace it: " + ec.message());
  }
  return {};
}

SavedPoses freshPoses(const SavedPoses& poses, std::int64_t nowUnixMs, double maxAgeS) {
  SavedPoses out;
  for (const auto& [id, s] : poses) {
    if (static_cast<double>(nowUnixMs - s.savedUnixMs) <= maxAgeS * 1000.0) {
      out[id] = s;
    }
  }
  return out;
}

}  // namespace fleet::agent
