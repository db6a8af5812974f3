#pragma once

// Samples a service refused (or repaired), counted by topic and reason, for its stats output.

#include <cstdint>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <string>

namespace fleet::validation {

/// Why one sample was refused: `reason` is a short code to count by ("non_finite", "id", ...),
/// `detail` names the field and the value for a log line.
struct Rejection {
  std::string topic;
  std::string reason;
  std::string detail;
};

/// Counts by topic and reason. Thread-safe: a service's DDS thread counts while its stats are read.
class Rejections {
 public:
  void count(const Rejection& r);
  /// A sample taken after repairing free text in it (invalid UTF-8 replaced).
  void repaired(const std::string& topic);

  [[nodiscard]] std::uint64_t total() const;
  /// Refused samples of `topic` for `reason` (0 when none).
  [[nodiscard]] std::uint64_t count(const std::string& topic, const std::string& reason) const;
  [[nodiscard]] std::uint64_t repairedCount(const std::string& topic) const;
  /// `{"rejected": {"TaskStatus": {"utf8": 1}}, "repaired": {"TaskStatus": 2}, "rejected_total": n}`.
  [[nodiscard]] nlohmann::json toJson() const;

 private:
  mutable std::mutex m_;
  std::map<std::string, std::map<std::string, std::uint64_t>> rejected_;
  std::map<std::string, std::uint64_t> repaired_;
  std::uint64_t total_ = 0;
};

}  // namespace fleet::validation
