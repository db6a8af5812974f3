#include "fleet/core/logging.hpp"

#include <spdlog/pattern_formatter.h>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cstdio>
#include <ctime>
#include <stdexcept>
#include <utility>
#include <vector>

namespace fleet::logging {
namespace {

std::vector<std::pair<std::string, std::string>>& fields() {
  static std::vector<std::pair<std::string, std::string>> f;
  return f;
}

thread_local std::vector<std::pair<std::string, std::string>> tScoped;

/// One JSON object per line: {"time":"...Z","level":"info","service":"...","msg":"...",...}.
class JsonFormatter : public spdlog::formatter {
 public:
  void format(const spdlog::details::log_msg& msg, spdlog::memory_buf_t& dest) override {
    const auto t = msg.time.time_since_epoch();
    const auto secs = std::chrono::duration_cast<std::chrono::seconds>(t);
    const auto ms = std::chrono::duration_cast<std::chrono::milliseconds>(t - secs).count();
    const std::time_t tt = secs.count();
    std::tm tm{};
    gmtime_r(&tt, &tm);
    char stamp[96];
    std::snprintf(stamp, sizeof(stamp), "%04d-%02d-%02dT%02d:%02d:%02d.%03dZ", tm.tm_year + 1900,
                  tm.tm_mon + 1, tm.tm_mday, tm.tm_hour, tm.tm_min, tm.tm_sec, static_cast<int>(ms));
    std::string line =
        "{\"time\":\"" + std::string(stamp) + "\",\"level\":" +
        jsonString(std::string(spdlog::level::to_string_view(msg.level).data(),
                               spdlog::level::to_string_view(msg.level).size())) +
        ",\"service\":" + jsonString(std::string(msg.logger_name.data(), msg.logger_name.size())) +
        ",\"msg\":" + jsonString(std::string(msg.payload.data(), msg.payload.size()));
    std::vector<std::string> seen;
    // Innermost scoped field first, then the process-wide ones; each key once.
    auto add = [&](const std::string& k, const std::string& v) {
      if (std::find(seen.begin(), seen.end(), k) == seen.end() && k != "time" && k != "level" &&
          k != "service" && k != "msg") {
        line += "," + jsonString(k) + ":" + jsonString(v);
        seen.push_back(k);
      }
    };
    for (auto it = tScoped.rbegin(); it != tScoped.rend(); ++it) {
      add(it->first, it->second);
    }
    for (const auto& [k, v] : fields()) {
      add(k, v);
    }
    line += "}\n";
    dest.append(line.data(), line.data() + line.size());
  }
  [[nodiscard]] std::unique_ptr<spdlog::formatter> clone() const override {
    return std::make_unique<JsonFormatter>();
  }
};

}  // namespace

std::string jsonString(const std::string& s) {
  std::string out = "\"";
  for (const char ch : s) {
    const auto c = static_cast<unsigned char>(ch);
    switch (c) {
      case '"':
        out += "\\\"";
        break;
      case '\\':
        out += "\\\\";
        break;
      case '\n':
        out += "\\n";
        break;
      case '\r':
        out += "\\r";
        break;
      case '\t':
        out += "\\t";
        break;
      default:
        if (c < 0x20) {
          char buf[8];
          std::snprintf(buf, sizeof(buf), "\\u%04x", c);
          out += buf;
        } else {
          out += ch;
        }
    }
  }
  return out + "\"";
}

ScopedField::ScopedField(std::string key, std::string value) {
  tScoped.emplace_back(std::move(key), std::move(value));
}
ScopedField::~ScopedField() {
  tScoped.pop_back();
}

void setField(const std::string& key, const std::string& value) {
  for (auto& [k, v] : fields()) {
    if (k == key) {
      v = value;
      return;
    }
  }
  fields().emplace_back(key, value);
}

void setup(const std::string& service, const std::string& level, const std::string& format) {
  const auto lvl = spdlog::level::from_str(level);
  // from_str maps unknown names to "off"; that silently hides everything, so refuse instead.
  if (lvl == spdlog::level::off && level != "off") {
    throw std::invalid_argument("unknown log level \"" + level +
                                "\" (expected trace, debug, info, warn, error, critical or off)");
  }
  if (format != "text" && format != "json") {
    throw std::invalid_argument("unknown log format \"" + format + "\" (expected text or json)");
  }
  auto logger = spdlog::get(service);
  if (!logger) {
    logger = spdlog::stderr_color_mt(service);
  }
  if (format == "json") {
    logger->set_formatter(std::make_unique<JsonFormatter>());
  } else {
    logger->set_pattern("%Y-%m-%dT%H:%M:%S.%e %n %^%l%$ %v");
  }
  logger->set_level(lvl);
  spdlog::set_default_logger(logger);
}

}  // namespace fleet::logging
