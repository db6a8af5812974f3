#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "fleet/scenario/scenario.hpp"

namespace fleet::sim::test {

/// A closed room of w x h cells ('@' border) at `res` m, no noise, given robots/humans added by the caller.
inline nlohmann::json room(int w, int h, double res = 0.5) {
  std::vector<std::string> rows;
  for (int r = 0; r < h; ++r) {
    std::string row(static_cast<std::size_t>(w), '.');
    if (r == 0 || r == h - 1) {
      row.assign(static_cast<std::size_t>(w), '@');
    }
    row.front() = '@';
    row.back() = '@';
    rows.push_back(row);
  }
  nlohmann::json j;
  j["name"] = "test-room";
  j["seed"] = 42;
  j["dt"] = 0.1;
  j["map"] = {{"rows", rows}, {"resolution", res}};
  j["robot_defaults"] = {
      {"radius", 0.3},
      {"wheel_base", 0.4},
      {"command_timeout_s", 0.5},
      {"limits", {{"v_max", 1.0}, {"v_min", -0.3}, {"w_max", 1.5}, {"accel_max", 1.0}, {"alpha_max", 3.0}}},
      {"noise", {{"slip_sigma", 0.0}, {"odom_sigma", 0.0}}},
      {"sensors", {{"range_sigma", 0.0}, {"compass_sigma", 0.0}, {"bearing_sigma", 0.0}}}};
  j["robots"] = nlohmann::json::array();
  return j;
}

inline Scenario parse(const nlohmann::json& j) {
  return parseScenario(j, "test.json", ".");
}

}  // namespace fleet::sim::test
