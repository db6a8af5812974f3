#pragma once

// Reads a VDA 5050 JSON object field by field; every refusal names the full path of the bad key
// ("order.nodes[2].sequenceId: expected an unsigned integer"), so a vendor sees what to fix.

#include <nlohmann/json.hpp>

#include <cstdint>
#include <initializer_list>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "fleet/core/bounded_json.hpp"

namespace fleet::vda5050::detail {

/// No message of the standard nests deeper or holds more values (a state with a long order is a
/// few thousand); the registry's byte limit (RegistryLimits) comes first.
inline constexpr JsonLimits kMessageJsonLimits{.maxBytes = 1 << 20, .maxDepth = 16, .maxElements = 100'000};

class BadField : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class JsonReader {
 public:
  JsonReader(const nlohmann::json& j, std::string path) : j_(j), path_(std::move(path)) {
    if (!j_.is_object()) {
      throw BadField(path_ + ": expected an object");
    }
  }

  [[nodiscard]] bool has(const char* key) const { return j_.contains(key) && !j_.at(key).is_null(); }

  [[nodiscard]] std::string str(const char* key) const {
    const auto& v = at(key);
    if (!v.is_string()) {
      throw BadField(where(key) + ": expected a string");
    }
    return v.get<std::string>();
  }
  [[nodiscard]] std::string oneOf(const char* key, std::initializer_list<const char*> allowed) const {
    std::string s = str(key);
    std::string list;
    for (const char* a : allowed) {
      if (s == a) {
        return s;
      }
      list += list.empty() ? a : std::string(", ") + a;
    }
    throw BadField(where(key) + ": '" + s + "' is not one of " + list);
  }
  [[nodiscard]] std::uint64_t uint(const char* key) const {
    const auto& v = at(key);
    if (!v.is_number_unsigned() && !(v.is_number_integer() && v.get<std::int64_t>() >= 0)) {
      throw BadField(where(key) + ": expected an unsigned integer");
    }
    return v.get<std::uint64_t>();
  }
  [[nodiscard]] double number(const char* key) const {
    const auto& v = at(key);
    if (!v.is_number()) {
      throw BadField(where(key) + ": expected a number");
    }
    return v.get<double>();
  }
  [[nodiscard]] bool boolean(const char* key) const {
    const auto& v = at(key);
    if (!v.is_boolean()) {
      throw BadField(where(key) + ": expected true or false");
    }
    return v.get<bool>();
  }
  [[nodiscard]] std::optional<std::string> optStr(const char* key) const {
    return has(key) ? std::optional(str(key)) : std::nullopt;
  }
  [[nodiscard]] std::optional<double> optNumber(const char* key) const {
    return has(key) ? std::optional(number(key)) : std::nullopt;
  }
  [[nodiscard]] std::optional<bool> optBoolean(const char* key) const {
    return has(key) ? std::optional(boolean(key)) : std::nullopt;
  }
  [[nodiscard]] JsonReader object(const char* key) const { return {at(key), where(key)}; }
  [[nodiscard]] const nlohmann::json& raw(const char* key) const { return at(key); }
  /// The elements of an array field, each with its indexed path.
  [[nodiscard]] std::vector<JsonReader> array(const char* key) const {
    const auto& v = at(key);
    if (!v.is_array()) {
      throw BadField(where(key) + ": expected an array");
    }
    std::vector<JsonReader> out;
    out.reserve(v.size());
    for (std::size_t i = 0; i < v.size(); ++i) {
      out.emplace_back(v[i], where(key) + "[" + std::to_string(i) + "]");
    }
    return out;
  }
  [[nodiscard]] std::vector<JsonReader> optArray(const char* key) const {
    return has(key) ? array(key) : std::vector<JsonReader>{};
  }
  [[nodiscard]] const std::string& path() const { return path_; }

 private:
  [[nodiscard]] std::string where(const char* key) const { return path_ + "." + key; }
  [[nodiscard]] const nlohmann::json& at(const char* key) const {
    if (!j_.contains(key)) {
      throw BadField(where(key) + ": missing");
    }
    return j_.at(key);
  }
  const nlohmann::json& j_;
  std::string path_;
};

}  // namespace fleet::vda5050::detail

#include "fleet/core/expected.hpp"
#include "fleet/vda5050/action.hpp"
#include "fleet/vda5050/header.hpp"
#include "fleet/vda5050/order.hpp"

namespace fleet::vda5050::detail {

Header readHeader(const JsonReader& r);
Action readAction(const JsonReader& r);
NodePosition readNodePosition(const JsonReader& r);
nlohmann::json nodePositionJson(const NodePosition& p);

/// Runs `read` on `j` and turns a refusal into an Error naming the bad key.
template <class T, class F>
Expected<T> parseAs(const nlohmann::json& j, const char* what, F&& read) {
  try {
    return read(JsonReader(j, what));
  } catch (const BadField& e) {
    return unexpected("vda5050.bad_field", e.what());
  } catch (const nlohmann::json::exception& e) {
    return unexpected("vda5050.bad_field", std::string(what) + ": " + e.what());
  }
}

/// The JSON of a message's text, parsed within kMessageJsonLimits (no message of the standard
/// nests deeper or holds more values), or an error saying the text is not JSON or which limit it
/// crossed (code "vda5050.json.too_large", ".too_deep", ".too_many_elements").
inline Expected<nlohmann::json> jsonOf(const std::string& text, const char* what) {
  auto j = parseBoundedJson(text, kMessageJsonLimits);
  if (!j) {
    const bool invalid = j.error().code == "json.invalid";
    return unexpected(invalid ? "vda5050.bad_json" : "vda5050." + j.error().code,
                      std::string(what) + ": " + (invalid ? "not valid JSON" : j.error().message));
  }
  return std::move(*j);
}

/// parse(json of text), or the error saying the text is not JSON.
template <class T>
Expected<T> parseTextWith(const std::string& text, const char* what,
                          Expected<T> (*parse)(const nlohmann::json&)) {
  auto j = jsonOf(text, what);
  if (!j) {
    return unexpected(j.error());
  }
  return parse(*j);
}

}  // namespace fleet::vda5050::detail
