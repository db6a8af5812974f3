#include "fleet/core/config.hpp"

#include <cmath>
#include <sstream>

#include "fleet/core/bounded_file.hpp"

namespace fleet {
namespace {

std::string joinProblems(const std::vector<std::string>& problems) {
  std::string out = problems.size() == 1
                        ? "invalid configuration: "
                        : "invalid configuration (" + std::to_string(problems.size()) + " problems):";
  for (const auto& p : problems) {
    out += problems.size() == 1 ? p : "\n  " + p;
  }
  return out;
}

std::string shortDump(const nlohmann::json& j) {
  std::string s = j.dump();
  if (s.size() > 40) {
    s = s.substr(0, 37) + "...";
  }
  return s;
}

std::string fmtNum(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

std::string describeRange(const Range& r, bool integral) {
  std::string what = integral ? "an integer" : "a number";
  const bool lo = std::isfinite(r.min);
  const bool hi = std::isfinite(r.max);
  if (lo && hi) {
    return what + " in " + (r.minExclusive ? "(" : "[") + fmtNum(r.min) + ", " + fmtNum(r.max) + "]";
  }
  if (lo) {
    return what + (r.minExclusive ? " > " : " >= ") + fmtNum(r.min);
  }
  if (hi) {
    return what + " <= " + fmtNum(r.max);
  }
  return what;
}

}  // namespace

std::string jsonTypeName(const nlohmann::json& j) {
  if (j.is_null())
    return "null";
  if (j.is_boolean())
    return "a boolean";
  if (j.is_number_integer() || j.is_number_unsigned())
    return "an integer";
  if (j.is_number())
    return "a number";
  if (j.is_string())
    return "a string";
  if (j.is_array())
    return "an array";
  return "an object";
}

ConfigError::ConfigError(std::vector<std::string> problems)
    : std::runtime_error(joinProblems(problems)), problems_(std::move(problems)) {}

Config::Config(std::shared_ptr<const nlohmann::json> root, const nlohmann::json* node, std::string origin,
               std::string prefix, std::shared_ptr<std::vector<std::string>> problems)
    : root_(std::move(root)),
      node_(node),
      origin_(std::move(origin)),
      prefix_(std::move(prefix)),
      problems_(std::move(problems)) {}

Config Config::fromJson(nlohmann::json doc, std::string origin) {
  auto root = std::make_shared<const nlohmann::json>(std::move(doc));
  auto problems = std::make_shared<std::vector<std::string>>();
  const nlohmann::json* node = root.get();
  Config c(root, node, std::move(origin), "", problems);
  if (!node->is_object()) {
    c.problem("", "expected a JSON object at the top level, got " + jsonTypeName(*node));
  }
  return c;
}

Config Config::fromText(std::string_view text, std::string origin) {
  nlohmann::json doc;
  try {
    doc = nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& e) {
    // Not only parse_error: a number beyond a double (1e999) is out_of_range.406 (found by fuzzing).
    throw ConfigError({origin + ": not valid JSON: " + e.what()});
  }
  return fromJson(std::move(doc), std::move(origin));
}

Config Config::fromFile(const std::string& path) {
  auto text = readBoundedFile(path, kConfigFileLimit, "config");
  if (!text) {
    throw ConfigError({text.error().message});
  }
  return fromText(*text, path);
}

std::string Config::keyPath(std::string_view path) const {
  if (prefix_.empty()) {
    return std::string(path);
  }
  if (path.empty()) {
    return prefix_;
  }
  return prefix_ + "." + std::string(path);
}

const nlohmann::json* Config::find(std::string_view path) const {
  const nlohmann::json* cur = node_;
  if (path.empty()) {
    return cur;
  }
  std::size_t start = 0;
  while (start <= path.size()) {
    const std::size_t dot = path.find('.', start);
    const std::string key(
        path.substr(start, dot == std::string_view::npos ? path.size() - start : dot - start));
    if (!cur->is_object()) {
      return nullptr;
    }
    auto it = cur->find(key);
    if (it == cur->end()) {
      return nullptr;
    }
    cur = &*it;
    if (dot == std::string_view::npos) {
      break;
    }
    start = dot + 1;
  }
  return cur;
}

bool Config::has(std::string_view path) const {
  return find(path) != nullptr;
}

void Config::problem(std::string_view path, std::string_view what) {
  const std::string key = keyPath(path);
  problems_->push_back(origin_ + ": " + (key.empty() ? std::string("(top level)") : key) + ": " +
                       std::string(what));
}

std::optional<double> Config::readNumber(std::string_view path, Range r, bool integral, bool required) {
  const nlohmann::json* j = find(path);
  const std::string expected = describeRange(r, integral);
  if (j == nullptr) {
    if (required) {
      problem(path, "missing; expected " + expected);
    }
    return std::nullopt;
  }
  if (!j->is_number() || (integral && !(j->is_number_integer() || j->is_number_unsigned()))) {
    problem(path, "expected " + expected + ", got " + jsonTypeName(*j) + " " + shortDump(*j));
    return std::nullopt;
  }
  const double v = j->get<double>();
  const bool belowMin = r.minExclusive ? !(v > r.min) : v < r.min;
  if (!std::isfinite(v) || belowMin || v > r.max) {
    problem(path, "expected " + expected + ", got " + shortDump(*j));
    return std::nullopt;
  }
  return v;
}

double Config::number(std::string_view path, double fallback, Range r) {
  return readNumber(path, r, false, false).value_or(fallback);
}
double Config::requireNumber(std::string_view path, Range r) {
  return readNumber(path, r, false, true).value_or(0.0);
}
std::int64_t Config::integer(std::string_view path, std::int64_t fallback, Range r) {
  auto v = readNumber(path, r, true, false);
  return v ? static_cast<std::int64_t>(*v) : fallback;
}
std::int64_t Config::requireInteger(std::string_view path, Range r) {
  auto v = readNumber(path, r, true, true);
  return v ? static_cast<std::int64_t>(*v) : 0;
}

bool Config::boolean(std::string_view path, bool fallback) {
  const nlohmann::json* j = find(path);
  if (j == nullptr) {
    return fallback;
  }
  if (!j->is_boolean()) {
    problem(path, "expected a boolean (true/false), got " + jsonTypeName(*j) + " " + shortDump(*j));
    return fallback;
  }
  return j->get<bool>();
}

std::optional<std::string> Config::readString(std::string_view path, const std::vector<std::string>& allowed,
                                              bool required) {
  const nlohmann::json* j = find(path);
  std::string expected = "a string";
  if (!allowed.empty()) {
    expected = "one of";
    for (std::size_t i = 0; i < allowed.size(); ++i) {
      expected += (i == 0 ? " \"" : ", \"") + allowed[i] + "\"";
    }
  }
  if (j == nullptr) {
    if (required) {
      problem(path, "missing; expected " + expected);
    }
    return std::nullopt;
  }
  if (!j->is_string()) {
    problem(path, "expected " + expected + ", got " + jsonTypeName(*j) + " " + shortDump(*j));
    return std::nullopt;
  }
  std::string v = j->get<std::string>();
  if (!allowed.empty()) {
    bool found = false;
    for (const auto& a : allowed) {
      found = found || a == v;
    }
    if (!found) {
      problem(path, "expected " + expected + ", got \"" + v + "\"");
      return std::nullopt;
    }
  }
  return v;
}

std::string Config::string(std::string_view path, std::string fallback,
                           const std::vector<std::string>& allowed) {
  return readString(path, allowed, false).value_or(std::move(fallback));
}
std::string Config::requireString(std::string_view path, const std::vector<std::string>& allowed) {
  return readString(path, allowed, true).value_or(std::string{});
}

Config Config::child(std::string_view path, bool required) {
  static const nlohmann::json kEmpty = nlohmann::json::object();
  const nlohmann::json* j = find(path);
  if (j == nullptr) {
    if (required) {
      problem(path, "missing; expected an object");
    }
    return Config(root_, &kEmpty, origin_, keyPath(path), problems_);
  }
  if (!j->is_object()) {
    problem(path, "expected an object, got " + jsonTypeName(*j));
    return Config(root_, &kEmpty, origin_, keyPath(path), problems_);
  }
  return Config(root_, j, origin_, keyPath(path), problems_);
}

std::vector<Config> Config::array(std::string_view path, bool required) {
  std::vector<Config> out;
  const nlohmann::json* j = find(path);
  if (j == nullptr) {
    if (required) {
      problem(path, "missing; expected an array");
    }
    return out;
  }
  if (!j->is_array()) {
    problem(path, "expected an array, got " + jsonTypeName(*j));
    return out;
  }
  out.reserve(j->size());
  for (std::size_t i = 0; i < j->size(); ++i) {
    const std::string p = keyPath(path) + "[" + std::to_string(i) + "]";
    out.push_back(Config(root_, &(*j)[i], origin_, p, problems_));
    if (!(*j)[i].is_object()) {
      out.back().problem("", "expected an object, got " + jsonTypeName((*j)[i]));
    }
  }
  return out;
}

void Config::rejectUnknownKeys(const std::vector<std::string>& known) {
  if (!node_->is_object()) {
    return;
  }
  for (const auto& [key, value] : node_->items()) {
    bool found = false;
    for (const auto& k : known) {
      found = found || k == key;
    }
    if (!found) {
      std::string list;
      for (const auto& k : known) {
        list += (list.empty() ? "" : ", ") + k;
      }
      problem(key, "unknown key (known keys: " + list + ")");
    }
  }
}

void Config::finish() const {
  if (!problems_->empty()) {
    throw ConfigError(*problems_);
  }
}

}  // namespace fleet
