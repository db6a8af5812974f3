#pragma once

// docs/openapi.yaml as the tests read it: its operations (path template and method), the path
// template a request path falls under, and whether a response conforms to what the document says
// for its path, method and status (a status the operation does not list falls to its `default`;
// a JSON body is checked against the schema by SchemaCheck; a response the document gives no
// content must have no body). Needs yaml-cpp.

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <regex>
#include <set>
#include <string>
#include <vector>

#include "json_schema_check.hpp"

namespace fleet::test {

/// YAML as JSON: quoted scalars are strings; plain ones are booleans, null, integers or numbers
/// when they read as one (YAML 1.2's core schema, as node's js-yaml reads the file), else strings.
inline nlohmann::json yamlToJson(const YAML::Node& n) {
  using nlohmann::json;
  switch (n.Type()) {
    case YAML::NodeType::Map: {
      json out = json::object();
      for (const auto& kv : n) {
        out[kv.first.Scalar()] = yamlToJson(kv.second);
      }
      return out;
    }
    case YAML::NodeType::Sequence: {
      json out = json::array();
      for (const auto& item : n) {
        out.push_back(yamlToJson(item));
      }
      return out;
    }
    case YAML::NodeType::Scalar: {
      const std::string& s = n.Scalar();
      if (n.Tag() == "!") {
        return s;  // quoted
      }
      if (s == "true" || s == "false") {
        return s == "true";
      }
      if (s == "null" || s == "~") {
        return nullptr;
      }
      static const std::regex integer(R"([-+]?[0-9]+)");
      static const std::regex number(R"([-+]?([0-9]+\.?[0-9]*|\.[0-9]+)([eE][-+]?[0-9]+)?)");
      if (std::regex_match(s, integer)) {
        return std::stoll(s);
      }
      if (std::regex_match(s, number)) {
        return std::stod(s);
      }
      return s;
    }
    default:
      return nullptr;
  }
}

class OpenApiContract {
 public:
  using json = nlohmann::json;

  explicit OpenApiContract(const std::filesystem::path& file)
      : doc_(yamlToJson(YAML::LoadFile(file.string()))), schemas_(doc_) {}
  OpenApiContract(const OpenApiContract&) = delete;  // schemas_ refers to doc_
  OpenApiContract& operator=(const OpenApiContract&) = delete;

  /// The document shipped in docs/, read once per test program.
  static const OpenApiContract& shipped() {
    static const OpenApiContract spec(std::filesystem::path(FLEET_SOURCE_DIR) / "docs/openapi.yaml");
    return spec;
  }

  [[nodiscard]] const json& document() const { return doc_; }

  struct Operation {
    std::string method;  // upper case: "GET"
    std::string path;    // as the document spells it: "/v1/tasks/{id}"
    const json* spec;
  };
  [[nodiscard]] std::vector<Operation> operations() const {
    std::vector<Operation> out;
    for (const auto& [path, item] : doc_.at("paths").items()) {
      for (const auto& [method, op] : item.items()) {
        if (kMethods.contains(method)) {
          std::string upper = method;
          std::transform(upper.begin(), upper.end(), upper.begin(), ::toupper);
          out.push_back({upper, path, &op});
        }
      }
    }
    return out;
  }

  /// The operation a request falls under: the path template that matches `path` (a parameter
  /// stands for one non-empty segment), the one with fewest parameters when several do.
  [[nodiscard]] std::optional<Operation> operationFor(const std::string& method,
                                                      const std::string& path) const {
    std::optional<Operation> best;
    std::size_t bestParams = 0;
    for (auto& op : operations()) {
      const std::string templ = op.path;
      const std::size_t params = static_cast<std::size_t>(std::count(templ.begin(), templ.end(), '{'));
      if (op.method == method && std::regex_match(path, templateRegex(templ)) &&
          (!best || params < bestParams)) {
        best = op;
        bestParams = params;
      }
    }
    return best;
  }

  /// What is wrong with a response, one line each naming the request and the field; empty when it
  /// conforms. `contentType` as sent (parameters such as "; charset=utf-8" are ignored).
  [[nodiscard]] std::vector<std::string> checkResponse(const std::string& method, const std::string& path,
                                                       int status, std::string contentType,
                                                       const std::string& body) const {
    const std::string who = method + " " + path + " -> " + std::to_string(status);
    std::vector<std::string> out;
    contentType = contentType.substr(0, contentType.find(';'));
    const auto op = operationFor(method, path);
    json response;
    if (!op) {
      // No route: the server's own error body.
      response = doc_.at("components").at("responses").at("Problem");
    } else {
      const json& responses = op->spec->at("responses");
      const std::string code = std::to_string(status);
      if (responses.contains(code)) {
        response = responses[code];
      } else if (responses.contains("default")) {
        response = responses["default"];
      } else {
        return {who + ": status " + code + " is not documented for " + op->method + " " + op->path +
                " (and it has no default response)"};
      }
      if (response.contains("$ref")) {
        response = doc_.at(json::json_pointer(response["$ref"].get<std::string>().substr(1)));
      }
    }
    if (!response.contains("content")) {
      if (!body.empty()) {
        out.push_back(who + ": the document gives this response no body, but it has " +
                      std::to_string(body.size()) + " bytes of " + contentType);
      }
      return out;
    }
    const json& content = response["content"];
    if (!content.contains(contentType)) {
      out.push_back(who + ": content type \"" + contentType + "\" is not one the document gives (" +
                    content.dump() + ")");
      return out;
    }
    if (contentType != "application/json") {
      return out;  // text, pages, event streams: the type is all there is to check
    }
    const json value = json::parse(body, nullptr, false);
    if (value.is_discarded()) {
      out.push_back(who + ": the body is not JSON");
      return out;
    }
    for (auto& p : schemas_.problems(value, content[contentType].at("schema"))) {
      out.push_back(who + ": " + p);
    }
    return out;
  }

 private:
  static inline const std::set<std::string> kMethods = {"get",     "put",  "post",  "delete",
                                                        "options", "head", "patch", "trace"};

  static std::regex templateRegex(const std::string& templ) {
    static const std::regex param(R"(\{[^}]+\})");
    static const std::regex special(R"([.^$|()\[\]*+?\\])");
    const std::string escaped = std::regex_replace(templ, special, R"(\$&)");
    return std::regex(std::regex_replace(escaped, param, "[^/]+"));
  }

  json doc_;
  SchemaCheck schemas_;
};

}  // namespace fleet::test
