#pragma once

#include <cstdint>
#include <limits>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace fleet {

/// Every problem found in a config file, each naming the file, the key path and what was expected.
class ConfigError : public std::runtime_error {
 public:
  explicit ConfigError(std::vector<std::string> problems);
  [[nodiscard]] const std::vector<std::string>& problems() const { return problems_; }

 private:
  std::vector<std::string> problems_;
};

/// "a string", "an integer", "an object"...: how error messages name a JSON value's type.
std::string jsonTypeName(const nlohmann::json& j);

struct Range {
  double min = -std::numeric_limits<double>::infinity();
  double max = std::numeric_limits<double>::infinity();
  bool minExclusive = false;
};

/// Reads typed values out of a JSON document and collects every problem instead of stopping at
/// the first, so one run of a service tells the operator everything wrong with the file.
///
/// Paths are dot-separated keys ("risk.levels"); array elements are addressed by child configs.
/// Getters return the default (or a neutral value for required keys) when the value is wrong and
/// record a problem; call finish() once all keys are read, which throws ConfigError if any
/// problem was recorded.
class Config {
 public:
  /// Parses a file. Unreadable files and JSON syntax errors throw ConfigError at once.
  static Config fromFile(const std::string& path);
  static Config fromJson(nlohmann::json doc, std::string origin);
  /// Parses text (e.g. an HTTP body or an inline config); origin names it in messages.
  static Config fromText(std::string_view text, std::string origin);

  [[nodiscard]] bool has(std::string_view path) const;
  [[nodiscard]] const nlohmann::json* find(std::string_view path) const;

  double number(std::string_view path, double fallback, Range r = {});
  double requireNumber(std::string_view path, Range r = {});
  std::int64_t integer(std::string_view path, std::int64_t fallback, Range r = {});
  std::int64_t requireInteger(std::string_view path, Range r = {});
  bool boolean(std::string_view path, bool fallback);
  std::string string(std::string_view path, std::string fallback,
                     const std::vector<std::string>& allowed = {});
  std::string requireString(std::string_view path, const std::vector<std::string>& allowed = {});

  /// A sub-object sharing this config's problem list. Missing keys give an empty object
  /// (and a problem when required).
  Config child(std::string_view path, bool required = false);
  /// Elements of an array of objects, each a Config addressed as path[i].
  std::vector<Config> array(std::string_view path, bool required = false);

  /// Records a problem for every key of this object that is not in `known` (typos are errors).
  void rejectUnknownKeys(const std::vector<std::string>& known);
  /// Records a problem at `path` of this config (for checks across several keys).
  void problem(std::string_view path, std::string_view what);

  [[nodiscard]] bool ok() const { return problems_->empty(); }
  [[nodiscard]] const std::vector<std::string>& problems() const { return *problems_; }
  /// Throws ConfigError listing every problem recorded so far (through this config or its children).
  void finish() const;

  [[nodiscard]] const nlohmann::json& json() const { return *node_; }
  [[nodiscard]] const std::string& origin() const { return origin_; }
  /// The full key path of `path` below this config, as it appears in messages.
  [[nodiscard]] std::string keyPath(std::string_view path) const;

 private:
  Config(std::shared_ptr<const nlohmann::json> root, const nlohmann::json* node, std::string origin,
         std::string prefix, std::shared_ptr<std::vector<std::string>> problems);

  std::optional<double> readNumber(std::string_view path, Range r, bool integral, bool required);
  std::optional<std::string> readString(std::string_view path, const std::vector<std::string>& allowed,
                                        bool required);

  std::shared_ptr<const nlohmann::json> root_;
  const nlohmann::json* node_;
  std::string origin_;
  std::string prefix_;
  std::shared_ptr<std::vector<std::string>> problems_;
};

}  // namespace fleet
