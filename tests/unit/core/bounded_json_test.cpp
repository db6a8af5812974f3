// parseBoundedJson refuses hostile shapes (deep nesting, floods of values, oversized text) with an
// error naming the limit, before building a document; escapeForLog keeps a log line one line.

#include "fleet/core/bounded_json.hpp"

#include <gtest/gtest.h>

#include "fleet/core/log_text.hpp"

using namespace fleet;

TEST(BoundedJson, ParsesWhatStaysWithinTheLimits) {
  auto j = parseBoundedJson(R"({"a": [1, 2, {"b": null}], "c": "x"})", {});
  ASSERT_TRUE(j) << j.error().message;
  EXPECT_EQ((*j)["a"][2]["b"], nullptr);
  // Exactly at the limits is fine: depth 2, 4 values.
  EXPECT_TRUE(parseBoundedJson("[[1, 2]]", {.maxBytes = 8, .maxDepth = 2, .maxElements = 4}));
}

TEST(BoundedJson, RefusesAMegabyteOfOpeningBracketsAsTooDeep) {
  const auto j = parseBoundedJson(std::string(1 << 20, '['), {.maxBytes = 2 << 20});
  ASSERT_FALSE(j);
  EXPECT_EQ(j.error().code, "json.too_deep");
  EXPECT_NE(j.error().message.find("max_depth"), std::string::npos) << j.error().message;
  EXPECT_NE(j.error().message.find("32"), std::string::npos) << j.error().message;
}

TEST(BoundedJson, RefusesDeepObjectsManyValuesAndLongTextNamingTheLimit) {
  std::string deep;
  for (int i = 0; i < 40; ++i) {
    deep += R"({"a":)";
  }
  deep += "1" + std::string(40, '}');
  EXPECT_EQ(parseBoundedJson(deep, {}).error().code, "json.too_deep");
  std::string many = "[0";
  for (int i = 0; i < 1000; ++i) {
    many += ",1";
  }
  many += "]";
  const auto m = parseBoundedJson(many, {.maxElements = 500});
  ASSERT_FALSE(m);
  EXPECT_EQ(m.error().code, "json.too_many_elements");
  EXPECT_NE(m.error().message.find("max_elements"), std::string::npos);
  const auto big = parseBoundedJson(many, {.maxBytes = 100});
  ASSERT_FALSE(big);
  EXPECT_EQ(big.error().code, "json.too_large");
  EXPECT_NE(big.error().message.find("max_bytes"), std::string::npos);
}

TEST(BoundedJson, RefusesBrokenTextWithoutThrowing) {
  for (const char* bad : {"", "[", "{\"a\":}", "nul", "[1,]", "\xff\xfe", "1 2"}) {
    const auto j = parseBoundedJson(bad, {});
    ASSERT_FALSE(j) << bad;
    EXPECT_EQ(j.error().code, "json.invalid") << bad;
  }
}

TEST(LogText, EscapesControlCharactersSoALineCannotBeForged) {
  EXPECT_EQ(escapeForLog("/v1/tasks\r\n200 access 1.2.3.4 admin"), "/v1/tasks\\r\\n200 access 1.2.3.4 admin");
  EXPECT_EQ(escapeForLog(std::string("a\0b\x1b[31m\t\"\\", 11)), "a\\u0000b\\u001b[31m\\t\\\"\\\\");
  EXPECT_EQ(escapeForLog("plain/path-ok"), "plain/path-ok");
  EXPECT_EQ(escapeForLog("\xff"), "\xef\xbf\xbd");  // invalid UTF-8 replaced
}
