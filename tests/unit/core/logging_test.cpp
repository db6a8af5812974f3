// --log-format json: one object per line with time, level, service, msg and the fields in scope;
// a multi-line message stays on one line. Text stays the default.

#include "fleet/core/logging.hpp"

#include <gtest/gtest.h>
#include <spdlog/spdlog.h>

#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>

using namespace fleet;

TEST(Logging, JsonIsOneObjectPerLineWithFieldsInScope) {
  logging::setup("svc_json", "info", "json");
  logging::setField("robot", "r1");
  testing::internal::CaptureStderr();
  {
    logging::ScopedField task("task", "t-7");
    logging::ScopedField inner("robot", "r2");  // the innermost value wins over the process-wide one
    spdlog::warn("two\nlines \"quoted\"");
  }
  spdlog::info("plain");
  spdlog::default_logger()->flush();
  const std::string out = testing::internal::GetCapturedStderr();
  std::istringstream in(out);
  std::vector<nlohmann::json> lines;
  for (std::string l; std::getline(in, l);) {
    lines.push_back(nlohmann::json::parse(l));  // throws (fails the test) on a line that is not JSON
  }
  ASSERT_EQ(lines.size(), 2u) << out;
  EXPECT_EQ(lines[0]["level"], "warning");
  EXPECT_EQ(lines[0]["service"], "svc_json");
  EXPECT_EQ(lines[0]["msg"], "two\nlines \"quoted\"");
  EXPECT_EQ(lines[0]["task"], "t-7");
  EXPECT_EQ(lines[0]["robot"], "r2");
  EXPECT_TRUE(lines[0]["time"].get<std::string>().ends_with("Z"));
  EXPECT_FALSE(lines[1].contains("task"));
  EXPECT_EQ(lines[1]["robot"], "r1");
  EXPECT_THROW(logging::setup("svc_json2", "info", "xml"), std::invalid_argument);
}

TEST(Logging, JsonStringEscapesControlCharacters) {
  EXPECT_EQ(logging::jsonString("a\tb\x01"), "\"a\\tb\\u0001\"");
}
