#include "fleet/vda5050/header.hpp"

#include <ctime>
#include <nlohmann/json.hpp>

#include "json_reader.hpp"

namespace fleet::vda5050 {

std::string topicName(const std::string& interface_name, const std::string& manufacturer,
                      const std::string& serial, const std::string& topic) {
  return interface_name + "/" + kMajorVersion + "/" + manufacturer + "/" + serial + "/" + topic;
}

std::string vehicleSubtree(const std::string& interface_name, const std::string& manufacturer,
                           const std::string& serial) {
  return topicName(interface_name, manufacturer, serial, "#");
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
