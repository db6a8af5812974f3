#pragma once

// A run folder's JSON and text files, as the load test's stages read and write them.

#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

namespace fleet::ctl {

/// The file's JSON; nothing when it is missing or not JSON.
std::optional<nlohmann::json> readJsonFile(const std::filesystem::path& path);

/// Writes (replaces) the file; false when it could not be written.
bool writeTextFile(const std::filesystem::path& path, const std::string& text);

}  // namespace fleet::ctl
