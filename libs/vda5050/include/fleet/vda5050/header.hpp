#pragma once

// The header every VDA 5050 message starts with, and the topic layout
// interfaceName/majorVersion/manufacturer/serialNumber/topic (specification 2.1, section 6.1).

#include <nlohmann/json_fwd.hpp>

#include <cstdint>
#include <optional>
#include <string>

namespace fleet::vda5050 {

inline constexpr const char* kVersion = "2.1.0";
inline constexpr const char* kMajorVersion = "v2";
inline constexpr const char* kDefaultInterface = "uagv";

struct Header {
  std::uint32_t headerId = 0;
  std::string timestamp;  // ISO 8601 UTC, "2026-11-26T03:00:00.000Z"
  std::string version = kVersion;
  std::string manufacturer;
  std::string serialNumber;
};

/// True when a message of protocol version `version` ("2.1.0") is one this master control speaks:
/// major 2, minor 0 or 1 (the minor versions it knows; a later one may mean what it cannot read).
bool speaksVersion(const std::string& version);

/// "uagv/v2/<manufacturer>/<serialNumber>/<topic>".
std::string topicName(const std::string& interface_name, const std::string& manufacturer,
                      const std::string& serial, const std::string& topic);
/// The subtree a vehicle is confined to: "uagv/v2/<manufacturer>/<serialNumber>/#".
std::string vehicleSubtree(const std::string& interface_name, const std::string& manufacturer,
                           const std::string& serial);
/// ISO 8601 UTC with milliseconds for nanoseconds since the epoch.
std::string isoTimestamp(std::int64_t ns_since_epoch);
/// Nanoseconds since the epoch of "YYYY-MM-DDTHH:MM:SS[.fraction]Z" (UTC, as isoTimestamp writes
/// it); nullopt for anything else (offsets other than Z are not accepted).
std::optional<std::int64_t> parseIsoTimestamp(const std::string& text);

void writeHeader(nlohmann::json& j, const Header& h);

}  // namespace fleet::vda5050
