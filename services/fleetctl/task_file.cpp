#include "task_file.hpp"

#include <charconv>
#include <set>
#include <sstream>

#include "fleet/core/bounded_file.hpp"

namespace fleet::ctl {
namespace {

/// Splits one CSV line; fields may be double-quoted with "" for a quote.
Expected<std::vector<std::string>> splitCsv(const std::string& line) {
  std::vector<std::string> out;
  std::string cur;
  bool quoted = false;
  for (std::size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quoted) {
      if (c == '"' && i + 1 < line.size() && line[i + 1] == '"') {
        cur += '"';
        ++i;
      } else if (c == '"') {
        quoted = false;
      } else {
        cur += c;
      }
    } else if (c == '"') {
      quoted = true;
    } else if (c == ',') {
      out.push_back(cur);
      cur.clear();
    } else if (c != '\r') {
      cur += c;
    }
  }
  if (quoted) {
    return unexpected("invalid", "unterminated quote");
  }
  out.push_back(cur);
  return out;
}

/// `text` cut at each `sep`.
std::vector<std::string> cut(const std::string& text, char sep) {
  std::vector<std::string> out(1);
  for (const char c : text) {
    if (c == sep) {
      out.emplace_back();
    } else {
      out.back() += c;
    }
  }
  return out;
}

}  // namespace

Expected<nlohmann::json> stepsFromText(const std::string& text) {
  nlohmann::json steps = nlohmann::json::array();
  int n = 0;
  for (const auto& one : cut(text, ';')) {
    ++n;
    const auto parts = cut(one, ':');
    if (parts.size() > 4 || parts[0].empty()) {
      return unexpected("invalid", "step " + std::to_string(n) + " \"" + one +
                                       "\": expected action:station[:load_id[:seconds]]");
    }
    nlohmann::json step = {{"action", parts[0]}};
    if (parts.size() > 1 && !parts[1].empty()) {
      step["station"] = parts[1];
    }
    if (parts.size() > 2 && !parts[2].empty()) {
      step["load_id"] = parts[2];
    }
    if (parts.size() > 3 && !parts[3].empty()) {
      double s = 0;
      auto [p, ec] = std::from_chars(parts[3].data(), parts[3].data() + parts[3].size(), s);
      if (ec != std::errc() || p != parts[3].data() + parts[3].size() || s < 0) {
        return unexpected("invalid",
                          "step " + std::to_string(n) + ": expected seconds >= 0, got \"" + parts[3] + "\"");
      }
      step["duration_ns"] = static_cast<long long>(s * 1e9);
    }
    steps.push_back(std::move(step));
  }
  return steps;
}

std::string withoutBom(const std::string& text) {
  return text.rfind("\xEF\xBB\xBF", 0) == 0 ? text.substr(3) : text;
}

Expected<nlohmann::json> csvToTasks(const std::string& textIn, const std::string& origin) {
  // Excel's "CSV UTF-8" starts with a byte-order mark; without dropping it the first column would
  // be "\xEF\xBB\xBFid", an unknown column.
  const std::string text = withoutBom(textIn);
  static const std::set<std::string> kText = {"id", "kind", "pickup", "dropoff", "station", "robot"};
  static const std::set<std::string> kInt = {"priority", "deadline_ns"};
  static const std::set<std::string> kSeconds = {"load_s", "unload_s"};
  std::istringstream in(text);
  std::string line;
  std::vector<std::string> header;
  nlohmann::json tasks = nlohmann::json::array();
  std::vector<std::string> problems;
  int lineNo = 0;
  while (std::getline(in, line)) {
    ++lineNo;
    if (line.empty() || line[0] == '#') {
      continue;
    }
    auto fields = splitCsv(line);
    const std::string where = origin + ":" + std::to_string(lineNo);
    if (!fields) {
      problems.push_back(where + ": " + fields.error().message);
      continue;
    }
    if (header.empty()) {
      header = *fields;
      for (const auto& h : header) {
        if (!kText.count(h) && !kInt.count(h) && !kSeconds.count(h) && h != "steps") {
          problems.push_back(where + ": unknown column \"" + h + "\"");
        }
      }
      if (std::find(header.begin(), header.end(), "id") == header.end()) {
        problems.push_back(where + ": the header has no \"id\" column");
      }
      continue;
    }
    if (fields->size() != header.size()) {
      problems.push_back(where + ": " + std::to_string(fields->size()) + " fields, the header has " +
                         std::to_string(header.size()));
      continue;
    }
    nlohmann::json t = nlohmann::json::object();
    for (std::size_t i = 0; i < header.size(); ++i) {
      const std::string& col = header[i];
      const std::string& v = (*fields)[i];
      if (v.empty()) {
        continue;
      }
      if (col == "steps") {
        auto steps = stepsFromText(v);
        if (!steps) {
          problems.push_back(where + ": column steps: " + steps.error().message);
          continue;
        }
        t[col] = std::move(*steps);
      } else if (kText.count(col)) {
        t[col] = v;
      } else if (kInt.count(col)) {
        long long n = 0;
        auto [p, ec] = std::from_chars(v.data(), v.data() + v.size(), n);
        if (ec != std::errc() || p != v.data() + v.size()) {
          problems.push_back(where + ": column " + col + ": expected an integer, got \"" + v + "\"");
          continue;
        }
        t[col] = n;
      } else {
        double s = 0;
        auto [p, ec] = std::from_chars(v.data(), v.data() + v.size(), s);
        if (ec != std::errc() || p != v.data() + v.size() || s < 0) {
          problems.push_back(where + ": column " + col + ": expected seconds >= 0, got \"" + v + "\"");
          continue;
        }
        t[col == "load_s" ? "load_duration_ns" : "unload_duration_ns"] = static_cast<long long>(s * 1e9);
      }
    }
    tasks.push_back(t);
  }
  if (!problems.empty()) {
    std::string msg;
    for (const auto& p : problems) {
      msg += (msg.empty() ? "" : "\n") + p;
    }
    return unexpected("invalid", msg);
  }
  return tasks;
}

Expected<nlohmann::json> loadTaskFile(const std::string& path) {
  auto raw = readBoundedFile(path, kConfigFileLimit, "invalid");
  if (!raw) {
    return unexpected(raw.error());
  }
  const std::string text = withoutBom(*raw);
  if (path.size() >= 4 && path.substr(path.size() - 4) == ".csv") {
    return csvToTasks(text, path);
  }
  auto j = nlohmann::json::parse(text, nullptr, false);
  if (j.is_discarded()) {
    return unexpected("invalid", path + ": not valid JSON");
  }
  if (j.is_object() && j.contains("tasks")) {
    j = j["tasks"];
  }
  if (j.is_object()) {
    j = nlohmann::json::array({j});
  }
  if (!j.is_array()) {
    return unexpected("invalid", path + ": expected a task object, an array of tasks or {\"tasks\": [...]}");
  }
  return j;
}

}  // namespace fleet::ctl
