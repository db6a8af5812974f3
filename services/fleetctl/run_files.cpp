#include "run_files.hpp"

#include <fstream>

namespace fleet::ctl {

std::optional<nlohmann::json> readJsonFile(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) {
    return std::nullopt;
  }
  auto j = nlohmann::json::parse(in, nullptr, false);
  if (j.is_discarded()) {
    return std::nullopt;
  }
  return j;
}

bool writeTextFile(const std::filesystem::path& path, const std::string& text) {
  std::ofstream out(path);
  out << text;
  return static_cast<bool>(out);
}

}  // namespace fleet::ctl
