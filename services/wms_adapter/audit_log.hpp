#pragma once

// The audit log: one JSON line per state-changing request (every method but GET, HEAD and
// OPTIONS), refused ones included: when, who (the token's name), from where, what (method, path
// and what the handler says it changed, e.g. the task ids) and the outcome (status). Written to a
// file of its own (append-only, reopened when logrotate moves it) or, without one, to the
// service's log as "audit {...}".

#include <cstdint>
#include <mutex>
#include <string>

#include "http_names.hpp"

namespace fleet::wms {

class AuditLog {
 public:
  /// `path` empty: lines go to the service log. The file is created 0640 if missing.
  explicit AuditLog(std::string path);
  ~AuditLog();
  AuditLog(const AuditLog&) = delete;
  AuditLog& operator=(const AuditLog&) = delete;

  [[nodiscard]] static bool audited(const std::string& method);
  /// The line for a request (no trailing newline); `wallNs` is when it was answered.
  [[nodiscard]] static std::string line(const Request& req, const Response& res, std::int64_t wallNs);
  /// Writes the line if the request changes state. Thread-safe.
  void record(const Request& req, const Response& res, std::int64_t wallNs);
  [[nodiscard]] std::uint64_t writeFailures() const { return failures_; }

 private:
  void openLocked();
  std::mutex m_;
  std::string path_;
  int fd_ = -1;
  std::uint64_t inode_ = 0;
  std::uint64_t failures_ = 0;
};

}  // namespace fleet::wms
