#pragma once

// The one way configuration files are read (site.json, map side files and images, MovingAI maps,
// scenarios, service configs, task and token files): the path is opened without blocking, checked
// to be a regular file no larger than a stated limit, and only then read. A FIFO, a device such as
// /dev/zero, a directory or a 3 GB sparse file is refused at once, naming the file, instead of
// hanging the process or reading gigabytes before the parser complains.

#include <cstdint>
#include <string>

#include "fleet/core/expected.hpp"

namespace fleet {

/// Size limits per kind of file, in bytes (docs/operator-guide.md, "Limits on site and map files").
inline constexpr std::uint64_t kKiB = 1024;
inline constexpr std::uint64_t kMiB = 1024 * kKiB;
/// JSON documents: site.json, scenarios, service configs, task and station files.
inline constexpr std::uint64_t kConfigFileLimit = 64 * kMiB;
/// Small side files: ROS map YAML, the JSON side file of a PGM map.
inline constexpr std::uint64_t kSideFileLimit = 1 * kMiB;
/// Map data: PGM/PNG images, MovingAI .map and .scen files.
inline constexpr std::uint64_t kMapFileLimit = 512 * kMiB;
/// Secrets: bearer token files.
inline constexpr std::uint64_t kTokenFileLimit = 64 * kKiB;

/// The whole content of the regular file at `path`, at most `limit` bytes. Errors (code `code`)
/// name the path and the reason: cannot open (with strerror), not a regular file (a directory, a
/// FIFO, a device), larger than the limit (checked with fstat before reading, and again while
/// reading in case the file grows), or a read error. Never blocks on a FIFO, never throws.
Expected<std::string> readBoundedFile(const std::string& path, std::uint64_t limit,
                                      const std::string& code = "file");

}  // namespace fleet
