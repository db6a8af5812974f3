#pragma once

// The error bodies the dashboard's routes answer with.

#include <nlohmann/json.hpp>
#include <string>

namespace fleet::wms::dashboard_detail {

using nlohmann::json;

inline json problem(const std::string& code, const std::string& message) {
  return {{"error", code}, {"message", message}};
}

inline json invalidField(const std::string& path, const std::string& reason) {
  return {{"error", "invalid"}, {"fields", json::array({{{"path", path}, {"reason", reason}}})}};
}

}  // namespace fleet::wms::dashboard_detail
