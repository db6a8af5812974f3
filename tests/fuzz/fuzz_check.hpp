#pragma once

// What the fuzz targets share: a property violation is reported like a crash (libFuzzer keeps the
// input), and inputs that name files are kept to the fuzz data folder.

#include <cstdio>
#include <cstdlib>
#include <nlohmann/json.hpp>
#include <string>

namespace fleet::fuzz {

/// Aborts with `what` when `ok` is false: libFuzzer saves the input as a crash.
inline void require(bool ok, const char* what) {
  if (!ok) {
    std::fprintf(stderr, "fuzz property violated: %s\n", what);
    std::abort();
  }
}

/// Folder with the small map files the seeds refer to (tests/fuzz/data).
inline std::string dataDir() {
  return FLEET_FUZZ_DATA_DIR;
}

/// True when no string in `j` could name a file outside the data folder: an absolute path or a
/// parent step would let the fuzzer read /dev/zero or the whole disk, which tests the operating
/// system, not our parser.
inline bool staysInDataDir(const nlohmann::json& j) {
  if (j.is_string()) {
    const auto& s = j.get_ref<const std::string&>();
    return s.empty() || (s.front() != '/' && s.find("..") == std::string::npos);
  }
  if (j.is_structured()) {
    for (const auto& [key, value] : j.items()) {
      if (!staysInDataDir(value)) {
        return false;
      }
    }
  }
  return true;
}

}  // namespace fleet::fuzz
