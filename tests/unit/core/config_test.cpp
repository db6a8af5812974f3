#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <functional>

#include <filesystem>
#include <fstream>

#include "fleet/core/config.hpp"

using namespace fleet;
using ::testing::HasSubstr;

namespace {
std::string writeTemp(const std::string& name, const std::string& text) {
  const auto p = std::filesystem::temp_directory_path() / name;
  std::ofstream(p) << text;
  return p.string();
}

std::string messageOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}
}  // namespace

TEST(Config, ReadsTypedValues) {
  auto c = Config::fromText(R"({"risk": {"levels": 10, "rate_hz": 12.5, "model": "gaussian"}, "on": true})",
                            "inline");
  EXPECT_EQ(c.integer("risk.levels", 5, {1, 100}), 10);
  EXPECT_DOUBLE_EQ(c.number("risk.rate_hz", 10, {0, 100, true}), 12.5);
  EXPECT_EQ(c.string("risk.model", "overlap", {"overlap", "gaussian"}), "gaussian");
  EXPECT_TRUE(c.boolean("on", false));
  EXPECT_EQ(c.integer("absent", 7), 7);
  EXPECT_NO_THROW(c.finish());
}

TEST(Config, ErrorNamesFileKeyAndExpectation) {
  const auto path =
      writeTemp("fleet_cfg_bad.json", R"({"risk": {"levels": 0, "model": "magic", "rate_hz": "fast"}})");
  auto c = Config::fromFile(path);
  auto risk = c.child("risk");
  (void)risk.integer("levels", 10, {1, 100});
  (void)risk.string("model", "overlap", {"overlap", "gaussian"});
  (void)risk.number("rate_hz", 10, {0, 100, true});
  (void)c.requireString("name");
  ASSERT_EQ(c.problems().size(), 4u);
  const std::string msg = messageOf([&] { c.finish(); });
  EXPECT_THAT(msg, HasSubstr(path + ": risk.levels: expected an integer in [1, 100], got 0"));
  EXPECT_THAT(msg,
              HasSubstr(path + ": risk.model: expected one of \"overlap\", \"gaussian\", got \"magic\""));
  EXPECT_THAT(msg, HasSubstr(path + ": risk.rate_hz: expected a number in (0, 100], got a string \"fast\""));
  EXPECT_THAT(msg, HasSubstr(path + ": name: missing; expected a string"));
}

TEST(Config, SyntaxErrorAndMissingFile) {
  const auto path = writeTemp("fleet_cfg_syntax.json", "{\"a\": 1,,}");
  EXPECT_THAT(messageOf([&] { (void)Config::fromFile(path); }), HasSubstr(path + ": not valid JSON"));
  EXPECT_THAT(messageOf([&] { (void)Config::fromFile("/nonexistent/x.json"); }),
              HasSubstr("/nonexistent/x.json: cannot open the file"));
  EXPECT_THAT(messageOf([&] { Config::fromText("[1,2]", "arr").finish(); }),
              HasSubstr("arr: (top level): expected a JSON object"));
}

// Found by tests/fuzz (config): nlohmann reports a number beyond a double as out_of_range, not
// parse_error, and it escaped Config as something other than ConfigError.
TEST(Config, NumberBeyondADoubleIsAConfigError) {
  EXPECT_THAT(messageOf([&] { (void)Config::fromText(R"({"speed": 1e999})", "big.json"); }),
              HasSubstr("big.json: not valid JSON"));
}

TEST(Config, ArraysAndUnknownKeys) {
  auto c = Config::fromText(
      R"({"robots": [{"id": "r1", "radius": 0.3}, {"id": "r2", "radius": -1}, 5], "robtos": 1})", "scn.json");
  auto robots = c.array("robots", true);
  ASSERT_EQ(robots.size(), 3u);
  for (auto& r : robots) {
    (void)r.requireString("id");
    (void)r.requireNumber("radius", {0, 5, true});
  }
  c.rejectUnknownKeys({"robots"});
  const std::string msg = messageOf([&] { c.finish(); });
  EXPECT_THAT(msg, HasSubstr("scn.json: robots[1].radius: expected a number in (0, 5], got -1"));
  EXPECT_THAT(msg, HasSubstr("scn.json: robots[2]: expected an object, got an integer"));
  EXPECT_THAT(msg, HasSubstr("scn.json: robtos: unknown key (known keys: robots)"));
}
