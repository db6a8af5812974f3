// readBoundedFile: the one reader of configuration files refuses what is not a regular file of a
// sane size at once, naming the file, and never hangs or reads gigabytes first.

#include "fleet/core/bounded_file.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "fleet/core/config.hpp"

namespace fleet {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

class BoundedFile : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("bounded_file_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  fs::path dir_;
};

TEST_F(BoundedFile, ReadsARegularFileWholeUpToTheLimit) {
  std::ofstream(path("a.txt"), std::ios::binary) << std::string(100, 'x') << '\0' << "tail";
  const auto r = readBoundedFile(path("a.txt"), 105);
  ASSERT_TRUE(r) << r.error().message;
  EXPECT_EQ(r->size(), 105u);
  EXPECT_EQ(r->substr(101), "tail");
  std::ofstream(path("empty"));
  EXPECT_EQ(readBoundedFile(path("empty"), 10).value(), "");
}

TEST_F(BoundedFile, RefusesAFileOverTheLimitNamingItAndTheSizes) {
  std::ofstream(path("b.txt")) << std::string(11, 'x');
  const auto r = readBoundedFile(path("b.txt"), 10, "map_yaml");
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error().code, "map_yaml");
  EXPECT_THAT(r.error().message, HasSubstr(path("b.txt") + ": is 11 bytes, more than the limit of 10 bytes"));
}

TEST_F(BoundedFile, RefusesASparseThreeGigabyteFileWithoutReadingIt) {
  std::ofstream(path("sparse.pgm"));
  fs::resize_file(path("sparse.pgm"), std::uintmax_t{3} << 30);  // no blocks: a hole
  const auto r = readBoundedFile(path("sparse.pgm"), kMapFileLimit, "map_image");
  ASSERT_FALSE(r);
  EXPECT_THAT(r.error().message,
              HasSubstr(path("sparse.pgm") + ": is 3221225472 bytes, more than the limit"));
}

TEST_F(BoundedFile, RefusesAFifoWithoutWaitingForAWriter) {
  ASSERT_EQ(::mkfifo(path("fifo").c_str(), 0600), 0);
  const auto r = readBoundedFile(path("fifo"), kConfigFileLimit);
  ASSERT_FALSE(r);
  EXPECT_THAT(r.error().message, HasSubstr(path("fifo") + ": is a FIFO, expected a regular file"));
}

TEST_F(BoundedFile, RefusesDevicesAndDirectories) {
  const auto zero = readBoundedFile("/dev/zero", kMapFileLimit);
  ASSERT_FALSE(zero);
  EXPECT_THAT(zero.error().message, HasSubstr("/dev/zero: is a character device, expected a regular file"));
  const auto dir = readBoundedFile(dir_.string(), kMapFileLimit);
  ASSERT_FALSE(dir);
  EXPECT_THAT(dir.error().message, HasSubstr(": is a directory, expected a regular file"));
}

TEST_F(BoundedFile, AMissingFileNamesThePathAndTheReason) {
  const auto r = readBoundedFile(path("nothing.json"), kConfigFileLimit, "invalid");
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error().code, "invalid");
  EXPECT_THAT(r.error().message, HasSubstr(path("nothing.json") + ": cannot open the file: No such file"));
}

// Config::fromFile (every service's --config, site.json, scenarios) reads through it.
TEST_F(BoundedFile, ConfigFromFileRefusesAFifoAndDevZeroNamingTheFile) {
  ASSERT_EQ(::mkfifo(path("config.json").c_str(), 0600), 0);
  try {
    (void)Config::fromFile(path("config.json"));
    FAIL() << "a FIFO was read as a configuration";
  } catch (const ConfigError& e) {
    EXPECT_THAT(e.what(), HasSubstr(path("config.json") + ": is a FIFO"));
  }
  EXPECT_THROW((void)Config::fromFile("/dev/zero"), ConfigError);
}

}  // namespace
}  // namespace fleet
