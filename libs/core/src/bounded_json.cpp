#include "fleet/core/bounded_json.hpp"

#include <string>

namespace fleet {
namespace {

using json = nlohmann::json;

/// Counts depth and values; returning false stops the parse at once.
class Counter : public nlohmann::json_sax<json> {
 public:
  explicit Counter(const JsonLimits& l) : limits_(l) {}

  bool null() override { return value(); }
  bool boolean(bool) override { return value(); }
  bool number_integer(number_integer_t) override { return value(); }
  bool number_unsigned(number_unsigned_t) override { return value(); }
  bool number_float(number_float_t, const string_t&) override { return value(); }
  bool string(string_t&) override { return value(); }
  bool binary(binary_t&) override { return value(); }
  bool start_object(std::size_t) override { return open(); }
  bool key(string_t&) override { return true; }
  bool end_object() override { return close(); }
  bool start_array(std::size_t) override { return open(); }
  bool end_array() override { return close(); }
  bool parse_error(std::size_t position, const std::string&, const nlohmann::detail::exception&) override {
    error_ = Error{"json.invalid", "not valid JSON (at byte " + std::to_string(position) + ")"};
    return false;
  }

  [[nodiscard]] const Error& error() const { return error_; }

 private:
  bool value() {
    if (++elements_ > limits_.maxElements) {
      error_ = Error{"json.too_many_elements", "more than " + std::to_string(limits_.maxElements) +
                                                   " JSON values (limit max_elements)"};
      return false;
    }
    return true;
  }
  bool open() {
    if (++depth_ > limits_.maxDepth) {
      error_ = Error{"json.too_deep", "JSON nested deeper than " + std::to_string(limits_.maxDepth) +
                                          " levels (limit max_depth)"};
      return false;
    }
    return value();
  }
  bool close() {
    --depth_;
    return true;
  }

  const JsonLimits& limits_;
  std::size_t depth_ = 0;
  std::size_t elements_ = 0;
  Error error_{"json.invalid", "not valid JSON"};
};

}  // namespace

Expected<nlohmann::json> parseBoundedJson(std::string_view text, const JsonLimits& limits) {
  if (text.size() > limits.maxBytes) {
    return unexpected("json.too_large", "JSON text of " + std::to_string(text.size()) + " bytes, more than " +
                                            std::to_string(limits.maxBytes) + " (limit max_bytes)");
  }
  Counter counter(limits);
  bool ok = false;
  try {
    ok = json::sax_parse(text.begin(), text.end(), &counter, json::input_format_t::json, true);
  } catch (const std::exception&) {
    ok = false;
  }
  if (!ok) {
    return unexpected(counter.error());
  }
  auto j = json::parse(text.begin(), text.end(), nullptr, false);
  if (j.is_discarded()) {
    return unexpected("json.invalid", "not valid JSON");
  }
  return j;
}

}  // namespace fleet
