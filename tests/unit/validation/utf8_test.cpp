#include "fleet/validation/utf8.hpp"

#include <gtest/gtest.h>

using namespace fleet::validation;

TEST(Utf8, AcceptsWellFormedText) {
  EXPECT_TRUE(isValidUtf8(""));
  EXPECT_TRUE(isValidUtf8("blocked by a person"));
  EXPECT_TRUE(
      isValidUtf8("Gabelstapler \xC3\xBC"
                  "ber Regal \xE2\x82\xAC \xF0\x9F\x9A\x9A"));
}

TEST(Utf8, RefusesStrayOverlongSurrogateAndTruncatedBytes) {
  EXPECT_FALSE(isValidUtf8("\xFF"));
  EXPECT_FALSE(isValidUtf8("a\x80z"));            // continuation byte alone
  EXPECT_FALSE(isValidUtf8("\xC0\xAF"));          // overlong '/'
  EXPECT_FALSE(isValidUtf8("\xE0\x80\xAF"));      // overlong, 3 bytes
  EXPECT_FALSE(isValidUtf8("\xED\xA0\x80"));      // UTF-16 surrogate
  EXPECT_FALSE(isValidUtf8("\xF4\x90\x80\x80"));  // above U+10FFFF
  EXPECT_FALSE(isValidUtf8("\xE2\x82"));          // cut short
}

TEST(Utf8, RepairReplacesEachBadByteAndKeepsTheRest) {
  EXPECT_EQ(repairUtf8("ok"), "ok");
  EXPECT_EQ(repairUtf8("a\xFFz"), "a\xEF\xBF\xBDz");
  EXPECT_EQ(repairUtf8("\xE2\x82"), "\xEF\xBF\xBD\xEF\xBF\xBD");
  EXPECT_EQ(repairUtf8("\xC3\xBC\xFF"), "\xC3\xBC\xEF\xBF\xBD");
  EXPECT_TRUE(isValidUtf8(repairUtf8("\xC0\xAF\xED\xA0\x80\xF4\x90\x80\x80")));
}
