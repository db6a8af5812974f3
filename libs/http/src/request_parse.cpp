#include "fleet/http/request_parse.hpp"

#include <boost/beast/http.hpp>

namespace fleet::http {
namespace {

int hexValue(char c) {
  if (c >= '0' && c <= '9') {
    return c - '0';
  }
  if (c >= 'a' && c <= 'f') {
    return c - 'a' + 10;
  }
  if (c >= 'A' && c <= 'F') {
    return c - 'A' + 10;
  }
  return -1;
}

}  // namespace

std::string percentDecode(std::string_view s, bool plusIsSpace) {
  std::string out;
  out.reserve(s.size());
  for (std::size_t i = 0; i < s.size(); ++i) {
    if (s[i] == '%' && i + 2 < s.size() && hexValue(s[i + 1]) >= 0 && hexValue(s[i + 2]) >= 0) {
      out.push_back(static_cast<char>(hexValue(s[i + 1]) * 16 + hexValue(s[i + 2])));
      i += 2;
    } else if (plusIsSpace && s[i] == '+') {
      out.push_back(' ');
    } else {
      out.push_back(s[i]);
    }
  }
  return out;
}

void parseTarget(std::string_view target, Request& req) {
  const auto q = target.find('?');
  req.path = percentDecode(target.substr(0, q), false);
  if (q == std::string_view::npos) {
    return;
  }
  std::string_view rest = target.substr(q + 1);
  while (!rest.empty()) {
    const auto amp = rest.find('&');
    const std::string_view pair = rest.substr(0, amp);
    if (!pair.empty()) {
      const auto eq = pair.find('=');
      req.params.emplace(percentDecode(pair.substr(0, eq), true),
                         eq == std::string_view::npos ? "" : percentDecode(pair.substr(eq + 1), true));
    }
    if (amp == std::string_view::npos) {
      break;
    }
    rest = rest.substr(amp + 1);
  }
}

ParsedRequest parseRequestBytes(std::string_view bytes, const ServerLimits& limits) {
  namespace bhttp = boost::beast::http;
  ParsedRequest out;
  bhttp::request_parser<bhttp::string_body> parser;
  parser.body_limit(limits.maxBodyBytes);
  parser.header_limit(static_cast<std::uint32_t>(limits.maxHeaderBytes));
  boost::beast::error_code ec;
  std::size_t used = 0;
  while (used < bytes.size() && !parser.is_done()) {
    const auto n = parser.put(boost::asio::buffer(bytes.data() + used, bytes.size() - used), ec);
    if (ec == bhttp::error::need_more) {
      break;
    }
    if (ec) {
      out.outcome = ec == bhttp::error::body_limit || ec == bhttp::error::header_limit
                        ? ParsedRequest::Outcome::TooLarge
                        : ParsedRequest::Outcome::Malformed;
      out.error = ec.message();
      break;
    }
    if (n == 0) {
      break;
    }
    used += n;
  }
  if (parser.is_header_done()) {
    const auto& msg = parser.get();
    out.request.method = std::string(msg.method_string());
    out.request.target = std::string(msg.target());
    parseTarget(out.request.target, out.request);
    for (const auto& f : msg) {
      out.request.headers.emplace_back(std::string(f.name_string()), std::string(f.value()));
    }
  }
  if (out.error.empty() && parser.is_done()) {
    out.outcome = ParsedRequest::Outcome::Complete;
    out.request.body = parser.get().body();
  }
  return out;
}

}  // namespace fleet::http
