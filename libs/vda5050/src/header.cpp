#include "fleet/vda5050/header.hpp"

#include <cstdio>
#include <ctime>
#include <nlohmann/json.hpp>

#include "json_reader.hpp"

namespace fleet::vda5050 {

std::string topicName(const std::string& interface_name, const std::string& manufacturer,
                      const std::string& serial, const std::string& topic) {
  return interface_name + "/" + kMajorVersion + "/" + manufacturer + "/" + serial + "/" + topic;
}

bool speaksVersion(const std::string& version) {
  int major = -1;
  int minor = -1;
  int consumed = 0;
  if (std::sscanf(version.c_str(), "%3d.%3d%n", &major, &minor, &consumed) != 2) {
    return false;
  }
  const char next = version.c_str()[consumed];
  return major == 2 && minor >= 0 && minor <= 1 && (next == '\0' || next == '.');
}

std::string vehicleSubtree(const std::string& interface_name, const std::string& manufacturer,
                           const std::string& serial) {
  return topicName(interface_name, manufacturer, serial, "#");
}

std::optional<std::int64_t> parseIsoTimestamp(const std::string& text) {
  std::tm tm{};
  int consumed = 0;
  if (std::sscanf(text.c_str(), "%4d-%2d-%2dT%2d:%2d:%2d%n", &tm.tm_year, &tm.tm_mon, &tm.tm_mday,
                  &tm.tm_hour, &tm.tm_min, &tm.tm_sec, &consumed) != 6 ||
      consumed != 19 || tm.tm_mon < 1 || tm.tm_mon > 12 || tm.tm_mday < 1 || tm.tm_mday > 31 ||
      tm.tm_hour > 23 || tm.tm_min > 59 || tm.tm_sec > 60) {
    return std::nullopt;
  }
  std::size_t i = 19;
  std::int64_t frac_ns = 0;
  if (i < text.size() && text[i] == '.') {
    std::int64_t scale = 100'000'000;
    ++i;
    const std::size_t first = i;
    for (; i < text.size() && text[i] >= '0' && text[i] <= '9'; ++i) {
      frac_ns += (text[i] - '0') * scale;
      scale /= 10;
    }
    if (i == first) {
      return std::nullopt;
    }
  }
  if (i + 1 != text.size() || text[i] != 'Z') {
    return std::nullopt;
  }
  tm.tm_year -= 1900;
  tm.tm_mon -= 1;
  const std::time_t secs = timegm(&tm);
  return static_cast<std::int64_t>(secs) * 1'000'000'000 + frac_ns;
}

std::string isoTimestamp(std::int64_t ns_since_epoch) {
  const std::time_t secs = static_cast<std::time_t>(ns_since_epoch / 1'000'000'000);
  const auto ms = static_cast<int>((ns_since_epoch % 1'000'000'000) / 1'000'000);
  std::tm tm{};
  gmtime_r(&secs, &tm);
  char buf[32];
  const std::size_t n = std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%S", &tm);
  char out[48];
  std::snprintf(out, sizeof out, "%.*s.%03dZ", static_cast<int>(n), buf, ms < 0 ? 0 : ms);
  return out;
}

void writeHeader(nlohmann::json& j, const Header& h) {
  j["headerId"] = h.headerId;
  j["timestamp"] = h.timestamp;
  j["version"] = h.version;
  j["manufacturer"] = h.manufacturer;
  j["serialNumber"] = h.serialNumber;
}

namespace detail {

Header readHeader(const JsonReader& r) {
  Header h;
  h.headerId = static_cast<std::uint32_t>(r.uint("headerId"));
  h.timestamp = r.str("timestamp");
  h.version = r.str("version");
  h.manufacturer = r.str("manufacturer");
  h.serialNumber = r.str("serialNumber");
  return h;
}

}  // namespace detail
}  // namespace fleet::vda5050
