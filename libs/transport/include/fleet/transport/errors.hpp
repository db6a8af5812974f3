#pragma once

#include <stdexcept>
#include <string>

namespace fleet::transport {

/// A failed DDS call: names the call and carries Cyclone's return code and its text.
class DdsError : public std::runtime_error {
 public:
  DdsError(const std::string& what, int rc);
  [[nodiscard]] int code() const { return rc_; }

 private:
  int rc_;
};

/// A C++ message that cannot be put on the wire as it is (string or sequence over its IDL bound,
/// embedded NUL). Names the field; nothing is written.
class MessageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Throws DdsError when rc < 0 (Cyclone's convention for entity handles and return codes).
int check(int rc, const char* what);

}  // namespace fleet::transport
