#include "audit_log.hpp"

#include <fcntl.h>
#include <spdlog/spdlog.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <ctime>
#include <nlohmann/json.hpp>

#include "fleet/core/config.hpp"

namespace fleet::wms {
namespace {

std::string isoTime(std::int64_t ns) {
  const std::time_t s = static_cast<std::time_t>(ns / 1'000'000'000);
  std::tm tm{};
  gmtime_r(&s, &tm);
  char buf[40];
  const auto n = std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%S", &tm);
  char ms[8];
  std::snprintf(ms, sizeof ms, ".%03dZ", static_cast<int>((ns / 1'000'000) % 1000));
  return std::string(buf, n) + ms;
}

std::string outcomeOf(int status) {
  if (status == 207) {
    return "partial";
  }
  if (status < 300) {
    return "done";
  }
  return status < 500 ? "refused" : "failed";
}

}  // namespace

AuditLog::AuditLog(std::string path) : path_(std::move(path)) {
  std::lock_guard lock(m_);
  openLocked();
  if (!path_.empty() && fd_ < 0) {
    const int err = errno;
    throw ConfigError({"http.audit_log: cannot open \"" + path_ + "\" for appending: " + std::strerror(err)});
  }
}

AuditLog::~AuditLog() {
  if (fd_ >= 0) {
    ::close(fd_);
  }
}

void AuditLog::openLocked() {
  if (path_.empty()) {
    return;
  }
  if (fd_ >= 0) {
    ::close(fd_);
  }
  fd_ = ::open(path_.c_str(), O_WRONLY | O_APPEND | O_CREAT | O_CLOEXEC, 0640);
  struct stat st {};
  inode_ = fd_ >= 0 && ::fstat(fd_, &st) == 0 ? st.st_ino : 0;
}

bool AuditLog::audited(const std::string& method) {
  return method != "GET" && method != "HEAD" && method != "OPTIONS";
}

std::string AuditLog::line(const Request& req, const Response& res, std::int64_t wallNs) {
  nlohmann::ordered_json j = {{"time", isoTime(wallNs)},
                              {"who", req.principal.empty() ? "-" : req.principal},
                              {"remote", req.remote_addr},
                              {"method", req.method},
                              {"path", req.path},
                              {"status", res.status},
                              {"outcome", outcomeOf(res.status)}};
  if (!res.audit.empty()) {
    j["what"] = nlohmann::ordered_json::parse(res.audit, nullptr, false);
  }
  return j.dump(-1, ' ', false, nlohmann::ordered_json::error_handler_t::replace);
}

void AuditLog::record(const Request& req, const Response& res, std::int64_t wallNs) {
  if (!audited(req.method)) {
    return;
  }
  const std::string text = line(req, res, wallNs);
  if (path_.empty()) {
    spdlog::info("audit {}", text);
    return;
  }
  const std::string l = text + "\n";
  std::lock_guard lock(m_);
  // Moved away (logrotate) or deleted: start a new file at the path.
  struct stat st {};
  if (::stat(path_.c_str(), &st) != 0 || st.st_ino != inode_) {
    openLocked();
  }
  // One write(2) per line on an O_APPEND descriptor: lines never interleave.
  if (fd_ < 0 || ::write(fd_, l.data(), l.size()) != static_cast<ssize_t>(l.size())) {
    ++failures_;
    spdlog::error("audit log \"{}\": cannot write; the line was: {}", path_, text);
  }
}

}  // namespace fleet::wms
