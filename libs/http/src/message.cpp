#include <algorithm>
#include <cctype>
#include <nlohmann/json.hpp>
#include <string_view>

#include "error_response.hpp"
#include "fleet/http/message.hpp"

namespace fleet::http {
namespace {

bool sameName(std::string_view a, std::string_view b) {
  return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(), [](char x, char y) {
           return std::tolower(static_cast<unsigned char>(x)) == std::tolower(static_cast<unsigned char>(y));
         });
}

}  // namespace

namespace detail {

Response errorResponse(int status, const std::string& code, const std::string& message) {
  Response r;
  r.status = status;
  r.set_content(nlohmann::json{{"error", code}, {"message", message}}.dump(), "application/json");
  return r;
}

}  // namespace detail

std::string Request::get_header_value(const std::string& name) const {
  for (const auto& [k, v] : headers) {
    if (sameName(k, name)) {
      return v;
    }
  }
  return "";
}

bool Request::has_header(const std::string& name) const {
  return std::any_of(headers.begin(), headers.end(), [&](const auto& h) { return sameName(h.first, name); });
}

std::string Request::get_param_value(const std::string& name) const {
  auto it = params.find(name);
  return it == params.end() ? "" : it->second;
}

void Response::set_header(const std::string& name, const std::string& value) {
  for (auto& [k, v] : headers) {
    if (sameName(k, name)) {
      v = value;
      return;
    }
  }
  headers.emplace_back(name, value);
}

std::string Response::get_header_value(const std::string& name) const {
  for (const auto& [k, v] : headers) {
    if (sameName(k, name)) {
      return v;
    }
  }
  return "";
}

}  // namespace fleet::http
