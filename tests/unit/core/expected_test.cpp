#include <gtest/gtest.h>

#include "fleet/core/expected.hpp"
#include "fleet/core/logging.hpp"

using namespace fleet;

namespace {
Expected<int> half(int x) {
  if (x % 2 != 0) {
    return unexpected("odd", "cannot halve " + std::to_string(x));
  }
  return x / 2;
}
}  // namespace

TEST(Expected, ValueAndError) {
  auto a = half(4);
  ASSERT_TRUE(a);
  EXPECT_EQ(*a, 2);
  auto b = half(3);
  ASSERT_FALSE(b);
  EXPECT_EQ(b.error().code, "odd");
  EXPECT_EQ(b.value_or(-1), -1);
  EXPECT_THROW((void)b.value(), BadExpectedAccess);
}

TEST(Expected, Void) {
  Expected<void> ok;
  EXPECT_TRUE(ok);
  Expected<void> bad = unexpected("x", "y");
  EXPECT_FALSE(bad);
  EXPECT_EQ(bad.error().message, "y");
}

TEST(Logging, UnknownLevelIsRefused) {
  EXPECT_THROW(logging::setup("svc_bad", "verbose"), std::invalid_argument);
  EXPECT_NO_THROW(logging::setup("svc_ok", "warn"));
}
