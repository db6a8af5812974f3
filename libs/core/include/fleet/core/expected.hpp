#pragma once

#include <stdexcept>
#include <string>
#include <utility>
#include <variant>

namespace fleet {

/// What went wrong, in words a user can act on. `code` is for programs, `message` for people.
struct Error {
  std::string code;
  std::string message;
};

template <class E>
struct Unexpected {
  E error;
};

inline Unexpected<Error> unexpected(std::string code, std::string message) {
  return {Error{std::move(code), std::move(message)}};
}
template <class E>
Unexpected<E> unexpected(E e) {
  return {std::move(e)};
}

class BadExpectedAccess : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A value or a typed error (std::expected arrives in C++23; this is the subset we use).
template <class T, class E = Error>
class Expected {
 public:
  Expected(T value) : v_(std::in_place_index<0>, std::move(value)) {}  // NOLINT(google-explicit-constructor)
  template <class E2>
  Expected(Unexpected<E2> u) : v_(std::in_place_index<1>, E(std::move(u.error))) {}  // NOLINT

  [[nodiscard]] bool has_value() const { return v_.index() == 0; }
  explicit operator bool() const { return has_value(); }

  T& value() & {
    check();
    return std::get<0>(v_);
  }
  const T& value() const& {
    check();
    return std::get<0>(v_);
  }
  T&& value() && {
    check();
    return std::get<0>(std::move(v_));
  }
  [[nodiscard]] const E& error() const { return std::get<1>(v_); }
  T& operator*() & { return value(); }
  const T& operator*() const& { return value(); }
  T* operator->() { return &value(); }
  const T* operator->() const { return &value(); }
  template <class U>
  T value_or(U&& fallback) const& {
    return has_value() ? std::get<0>(v_) : static_cast<T>(std::forward<U>(fallback));
  }

 private:
  void check() const {
    if (!has_value()) {
      if constexpr (requires(const E& e) { e.message; }) {
        throw BadExpectedAccess(std::get<1>(v_).message);
      } else {
        throw BadExpectedAccess("Expected holds an error");
      }
    }
  }
  std::variant<T, E> v_;
};

/// Expected<void>: success or an error.
template <class E>
class Expected<void, E> {
 public:
  Expected() = default;
  template <class E2>
  Expected(Unexpected<E2> u) : err_(E(std::move(u.error))), ok_(false) {}  // NOLINT
  [[nodiscard]] bool has_value() const { return ok_; }
  explicit operator bool() const { return ok_; }
  [[nodiscard]] const E& error() const { return err_; }

 private:
  E err_{};
  bool ok_ = true;
};

}  // namespace fleet
