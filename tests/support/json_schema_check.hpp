#pragma once

// Checks a JSON value against an OpenAPI 3.0 schema object: the subset docs/openapi.yaml uses
// (type, nullable, enum, required, properties, additionalProperties, items, minItems, maxItems,
// minimum, maximum, pattern, oneOf, allOf and $ref into the document). A keyword outside it is
// itself a problem, so the spec cannot grow a rule this checker silently ignores. Each problem
// names where it is, as a JSON path from the body ("$.robots[0].mode").

#include <algorithm>
#include <nlohmann/json.hpp>
#include <regex>
#include <set>
#include <string>
#include <vector>

namespace fleet::test {

class SchemaCheck {
 public:
  /// `document` is the whole OpenAPI document ($refs are "#/components/schemas/Name").
  explicit SchemaCheck(const nlohmann::json& document) : doc_(document) {}

  /// Every way `value` breaks `schema`; empty when it conforms.
  [[nodiscard]] std::vector<std::string> problems(const nlohmann::json& value, const nlohmann::json& schema,
                                                  const std::string& where = "$") const {
    std::vector<std::string> out;
    check(value, schema, where, out);
    return out;
  }

 private:
  using json = nlohmann::json;

  /// The schema a {$ref} points at (followed through chains), or the schema itself.
  [[nodiscard]] const json* resolve(const json& schema, const std::string& where,
                                    std::vector<std::string>& out) const {
    const json* s = &schema;
    for (int hops = 0; s->is_object() && s->contains("$ref"); ++hops) {
      const std::string ref = (*s)["$ref"].get<std::string>();
      if (ref.rfind("#/", 0) != 0 || hops > 32) {
        out.push_back(where + ": schema $ref \"" + ref + "\" cannot be followed");
        return nullptr;
      }
      const json::json_pointer pointer(ref.substr(1));
      if (!doc_.contains(pointer)) {
        out.push_back(where + ": schema $ref \"" + ref + "\" names nothing in the document");
        return nullptr;
      }
      s = &doc_.at(pointer);
    }
    return s;
  }

  static std::string shown(const json& v) {
    std::string text = v.dump(-1, ' ', false, json::error_handler_t::replace);
    return text.size() > 80 ? text.substr(0, 77) + "..." : text;
  }

  static bool hasType(const json& v, const std::string& type) {
    if (type == "object") {
      return v.is_object();
    }
    if (type == "array") {
      return v.is_array();
    }
    if (type == "string") {
      return v.is_string();
    }
    if (type == "integer") {
      return v.is_number_integer();
    }
    if (type == "number") {
      return v.is_number();
    }
    if (type == "boolean") {
      return v.is_boolean();
    }
    return false;
  }

  void check(const json& v, const json& schemaIn, const std::string& at,
             std::vector<std::string>& out) const {
    const json* found = resolve(schemaIn, at, out);
    if (found == nullptr) {
      return;
    }
    const json& s = *found;
    if (!s.is_object()) {
      out.push_back(at + ": the schema is not an object");
      return;
    }
    static const std::set<std::string> known = {"type", "nullable", "enum", "required", "properties",
                                                "additionalProperties", "items", "minItems", "maxItems",
                                                "minimum", "maximum", "pattern", "oneOf", "allOf",
                                                // annotations: nothing to check
                                                "description", "example", "default", "title"};
    for (const auto& [key, unused] : s.items()) {
      if (!known.contains(key)) {
        out.push_back(at + ": schema keyword \"" + key + "\" is not understood by the test's checker");
      }
    }
    if (v.is_null() && s.value("nullable", false)) {
      return;
    }
    for (const auto& part : s.value("allOf", json::array())) {
      check(v, part, at, out);
    }
    if (s.contains("oneOf")) {
      checkOneOf(v, s["oneOf"], at, out);
    }
    if (s.contains("type") && !hasType(v, s["type"].get<std::string>())) {
      out.push_back(at + ": expected " + s["type"].get<std::string>() + ", got " + shown(v));
      return;  // the rest would only repeat it
    }
    if (s.contains("enum")) {
      const auto& options = s["enum"];
      if (std::find(options.begin(), options.end(), v) == options.end()) {
        out.push_back(at + ": " + shown(v) + " is not one of " + shown(options));
      }
    }
    if (v.is_number()) {
      if (s.contains("minimum") && v.get<double>() < s["minimum"].get<double>()) {
        out.push_back(at + ": " + shown(v) + " is below the minimum " + shown(s["minimum"]));
      }
      if (s.contains("maximum") && v.get<double>() > s["maximum"].get<double>()) {
        out.push_back(at + ": " + shown(v) + " is above the maximum " + shown(s["maximum"]));
      }
    }
    if (v.is_string() && s.contains("pattern") &&
        !std::regex_search(v.get<std::string>(), std::regex(s["pattern"].get<std::string>()))) {
      out.push_back(at + ": " + shown(v) + " does not match " + s["pattern"].get<std::string>());
    }
    if (v.is_array()) {
      checkArray(v, s, at, out);
    }
    if (v.is_object()) {
      checkObject(v, s, at, out);
    }
  }

  void checkOneOf(const json& v, const json& options, const std::string& at,
                  std::vector<std::string>& out) const {
    std::size_t matched = 0;
    std::vector<std::string> closest;
    for (const auto& option : options) {
      auto p = problems(v, option, at);
      if (p.empty()) {
        ++matched;
      } else if (closest.empty() || p.size() < closest.size()) {
        closest = std::move(p);
      }
    }
    if (matched == 0) {
      out.push_back(at + ": matches none of its " + std::to_string(options.size()) +
                    " oneOf schemas; the closest says:");
      out.insert(out.end(), closest.begin(), closest.end());
    } else if (matched > 1) {
      out.push_back(at + ": matches " + std::to_string(matched) + " of its oneOf schemas, not exactly one");
    }
  }

  void checkArray(const json& v, const json& s, const std::string& at, std::vector<std::string>& out) const {
    if (s.contains("minItems") && v.size() < s["minItems"].get<std::size_t>()) {
      out.push_back(at + ": " + std::to_string(v.size()) + " items, at least " + shown(s["minItems"]) +
                    " expected");
    }
    if (s.contains("maxItems") && v.size() > s["maxItems"].get<std::size_t>()) {
      out.push_back(at + ": " + std::to_string(v.size()) + " items, at most " + shown(s["maxItems"]) +
                    " expected");
    }
    if (s.contains("items")) {
      for (std::size_t i = 0; i < v.size(); ++i) {
        check(v[i], s["items"], at + "[" + std::to_string(i) + "]", out);
      }
    }
  }

  void checkObject(const json& v, const json& s, const std::string& at, std::vector<std::string>& out) const {
    for (const auto& name : s.value("required", json::array())) {
      if (!v.contains(name.get<std::string>())) {
        out.push_back(at + "." + name.get<std::string>() + ": required but missing");
      }
    }
    const json properties = s.value("properties", json::object());
    for (const auto& [name, value] : v.items()) {
      if (properties.contains(name)) {
        check(value, properties[name], at + "." + name, out);
      } else if (s.contains("additionalProperties")) {
        const auto& extra = s["additionalProperties"];
        if (extra.is_boolean() && !extra.get<bool>()) {
          out.push_back(at + "." + name + ": not in the schema (additionalProperties is false)");
        } else if (extra.is_object()) {
          check(value, extra, at + "." + name, out);
        }
      }
    }
  }

  const nlohmann::json& doc_;
};

}  // namespace fleet::test
