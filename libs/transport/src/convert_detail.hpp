#pragma once

// What the files copying C++ messages to and from the idlc-generated C structs share: strings and
// sequences within their IDL bounds (writing never truncates: a value over its bound is a
// MessageError naming the field), poses and enums.

#include <cstring>
#include <string>
#include <type_traits>
#include <vector>

#include "fleet/transport/dds.hpp"

namespace fleet::transport::convert_detail {

template <std::size_t N>
void putStr(char (&dst)[N], const std::string& s, const char* field) {
  if (s.size() > N - 1) {
    throw MessageError(std::string(field) + ": " + std::to_string(s.size()) + " bytes, at most " +
                       std::to_string(N - 1) + " allowed");
  }
  if (s.find('\0') != std::string::npos) {
    throw MessageError(std::string(field) + ": contains a NUL byte");
  }
  std::memcpy(dst, s.data(), s.size());
  dst[s.size()] = '\0';
}

template <std::size_t N>
std::string getStr(const char (&src)[N]) {
  return std::string(src, strnlen(src, N));
}

template <class Seq, class S, class F>
void putSeq(Seq& seq, const std::vector<S>& v, std::size_t bound, Arena& arena, const char* field, F&& conv) {
  using E = std::remove_pointer_t<decltype(seq._buffer)>;
  if (bound != 0 && v.size() > bound) {
    throw MessageError(std::string(field) + ": " + std::to_string(v.size()) + " elements, at most " +
                       std::to_string(bound) + " allowed");
  }
  E* buf = arena.alloc<E>(v.size());
  for (std::size_t i = 0; i < v.size(); ++i) {
    conv(v[i], buf[i]);
  }
  seq._buffer = buf;
  seq._length = static_cast<std::uint32_t>(v.size());
  seq._maximum = static_cast<std::uint32_t>(v.size());
  seq._release = false;
}

template <class Seq, class F>
auto getSeq(const Seq& seq, F&& conv) {
  using R = decltype(conv(*seq._buffer));
  std::vector<R> out;
  out.reserve(seq._length);
  for (std::uint32_t i = 0; i < seq._length; ++i) {
    out.push_back(conv(seq._buffer[i]));
  }
  return out;
}

inline fleet_Pose2D putPose(const Pose2& p) {
  return {p.x, p.y, p.theta};
}
inline Pose2 getPose(const fleet_Pose2D& p) {
  return {p.x, p.y, p.theta};
}

template <class E, class C>
E getEnum(C c, E maxValue) {
  const auto v = static_cast<int>(c);
  // A peer with a newer enum may send values we don't know; map them to the last (most generic).
  return (v < 0 || v > static_cast<int>(maxValue)) ? maxValue : static_cast<E>(v);
}

}  // namespace fleet::transport::convert_detail
