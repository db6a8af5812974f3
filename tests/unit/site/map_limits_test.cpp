// Map files are bounded before anything is read or allocated for them: a file that is not a regular
// file of a sane size (a FIFO, /dev/zero, a sparse 3 GB file) and a map whose cells or metres are
// beyond the limits (planning/map_limits.hpp) are refused with the file and the key named.

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "fleet/core/config.hpp"
#include "fleet/planning/map_io.hpp"
#include "fleet/planning/map_limits.hpp"
#include "fleet/site/ros_map.hpp"
#include "fleet/site/site_loader.hpp"

namespace fleet::site {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

class MapLimits : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("map_limits_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    write("map.pgm", "P2\n4 3\n255\n254 254 254 254\n254 254 254 254\n254 254 254 254\n");
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string write(const std::string& name, const std::string& text) const {
    std::ofstream(dir_ / name, std::ios::binary) << text;
    return path(name);
  }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  std::string yaml(const std::string& name, const std::string& image, const std::string& res,
                   const std::string& origin = "[0, 0, 0]") const {
    return write(name, "image: " + image + "\nresolution: " + res + "\norigin: " + origin + "\n");
  }
  std::string site(const std::string& name, const nlohmann::json& map) const {
    const nlohmann::json j = {{"format", "fleet-site/1"}, {"name", "limits"}, {"map", map}};
    return write(name, j.dump());
  }
  static std::vector<std::string> problemsOf(const std::string& sitePath) {
    try {
      (void)loadSite(sitePath, false);
    } catch (const ConfigError& e) {
      return e.problems();
    }
    return {};
  }
  fs::path dir_;
};

TEST_F(MapLimits, AHugeResolutionIsRefusedNamingTheSideFileAndTheKey) {
  const auto m = loadRosMap(yaml("huge.yaml", "map.pgm", "1000000"));
  ASSERT_FALSE(m);
  EXPECT_EQ(m.error().code, "map_size");
  EXPECT_THAT(m.error().message,
              HasSubstr(path("huge.yaml") + ": resolution: 1e+06 m per cell makes the map 4e+06 x 3e+06 m "
                                            "(limit 2000 m a side)"));
  // Through site.json: the site's file and key path, then the side file's.
  const auto problems = problemsOf(site("huge.site.json", {{"ros", "huge.yaml"}}));
  ASSERT_EQ(problems.size(), 1u);
  EXPECT_THAT(problems[0], HasSubstr(path("huge.site.json") + ": map.ros: " + path("huge.yaml") +
                                     ": resolution: 1e+06 m per cell"));
}

TEST_F(MapLimits, ATinyResolutionIsRefused) {
  const auto m = loadRosMap(yaml("tiny.yaml", "map.pgm", "1e-6"));
  ASSERT_FALSE(m);
  EXPECT_THAT(m.error().message, HasSubstr(path("tiny.yaml") + ": resolution: 1e-06 m per cell is finer than "
                                                               "the limit of 0.001 m"));
}

TEST_F(MapLimits, ARotatedMapIsBoundedByTheGridItBecomes) {
  // 4 x 3 cells of 400 m: 1600 x 1200 m fits; turned by 45 degrees its grid is 1980 x 1980 m... and
  // at 500 m a cell, 2475 m, over the limit.
  ASSERT_TRUE(loadRosMap(yaml("fits.yaml", "map.pgm", "400", "[0, 0, 0.7853981634]")));
  const auto m = loadRosMap(yaml("turned.yaml", "map.pgm", "500", "[0, 0, 0.7853981634]"));
  ASSERT_FALSE(m);
  EXPECT_THAT(m.error().message,
              HasSubstr(path("turned.yaml") + ": resolution: 500 m per cell makes the map"));
}

TEST_F(MapLimits, AFarOriginIsRefused) {
  const auto m = loadRosMap(yaml("far.yaml", "map.pgm", "0.05", "[1e12, 0, 0]"));
  ASSERT_FALSE(m);
  EXPECT_THAT(m.error().message, HasSubstr(path("far.yaml") + ": origin: (1e+12, 0) puts the map more than"));
}

TEST_F(MapLimits, TooManyCellsAreRefusedBeforeAllocating) {
  // 100000 x 100000 cells would be 10 GB of grid.
  const auto g =
      planning::parseMovingAiMap("type octile\nheight 100000\nwidth 100000\nmap\n", "big.map", 0.01);
  ASSERT_FALSE(g);
  EXPECT_THAT(
      g.error().message,
      HasSubstr("big.map: width x height: 100000 x 100000 makes the map 1e+10 cells (limit 67108864"));
  const auto w = problemsOf(
      site("wh.site.json", {{"warehouse", {{"width", 10000}, {"height", 10000}}}, {"resolution", 0.1}}));
  ASSERT_EQ(w.size(), 1u);
  EXPECT_THAT(w[0],
              HasSubstr(path("wh.site.json") + ": map.warehouse: width x height: 10000 x 10000 makes the "
                                               "map 1e+08 cells"));
  const auto rows = problemsOf(
      site("rows.site.json", {{"rows", {std::string(30, '.'), std::string(30, '.')}}, {"resolution", 100}}));
  ASSERT_EQ(rows.size(), 1u);
  EXPECT_THAT(rows[0], HasSubstr("resolution: 100 m per cell makes the map 3000 x 200 m"));
}

TEST_F(MapLimits, AMapAtTheLimitsLoads) {
  const double side = std::sqrt(planning::kMaxMapCells);  // 8192 cells
  EXPECT_TRUE(planning::checkMapSize(side, side, planning::kMaxMapSideM / side, {}, "m", "image"));
  EXPECT_FALSE(planning::checkMapSize(side + 1, side, 0.1, {}, "m", "image"));
  EXPECT_TRUE(planning::checkMapSize(1, 1, planning::kMinMapResolution, {-1e6, 1e6}, "m", "image"));
}

TEST_F(MapLimits, AFifoSideFileIsRefusedWithoutHanging) {
  ASSERT_EQ(::mkfifo(path("fifo.yaml").c_str(), 0600), 0);
  const auto m = loadRosMap(path("fifo.yaml"));
  ASSERT_FALSE(m);
  EXPECT_EQ(m.error().code, "map_yaml");
  EXPECT_THAT(m.error().message, HasSubstr(path("fifo.yaml") + ": is a FIFO, expected a regular file"));
}

TEST_F(MapLimits, ADeviceOrSparseImageIsRefusedWithoutReadingIt) {
  const auto zero = loadRosMap(yaml("zero.yaml", "/dev/zero", "0.05"));
  ASSERT_FALSE(zero);
  EXPECT_EQ(zero.error().code, "map_image");
  EXPECT_THAT(zero.error().message, HasSubstr("/dev/zero: is a character device"));
  EXPECT_THAT(zero.error().message, HasSubstr("(image of " + path("zero.yaml") + ")"));
  std::ofstream(dir_ / "sparse.pgm");
  fs::resize_file(dir_ / "sparse.pgm", std::uintmax_t{3} << 30);
  const auto sparse = loadRosMap(yaml("sparse.yaml", "sparse.pgm", "0.05"));
  ASSERT_FALSE(sparse);
  EXPECT_THAT(sparse.error().message,
              HasSubstr(path("sparse.pgm") + ": is 3221225472 bytes, more than the limit"));
}

TEST_F(MapLimits, EveryMapReaderGoesThroughTheBoundedReader) {
  ASSERT_EQ(::mkfifo(path("fifo.map").c_str(), 0600), 0);
  const auto movingAi = planning::loadMovingAiMap(path("fifo.map"));
  ASSERT_FALSE(movingAi);
  EXPECT_THAT(movingAi.error().message, HasSubstr(path("fifo.map") + ": is a FIFO"));
  const auto image = planning::loadImageMap("/dev/zero");
  ASSERT_FALSE(image);
  EXPECT_THAT(image.error().message, HasSubstr("/dev/zero: is a character device"));
  // site.json itself, and a bare map given where a site is expected.
  ASSERT_EQ(::mkfifo(path("fifo.site.json").c_str(), 0600), 0);
  EXPECT_THAT(problemsOf(path("fifo.site.json")),
              ::testing::ElementsAre(HasSubstr(path("fifo.site.json") + ": is a FIFO")));
  try {
    (void)loadSiteOrMap(path("fifo.map"));
    FAIL() << "a FIFO loaded as a map";
  } catch (const ConfigError& e) {
    EXPECT_THAT(e.what(), HasSubstr(path("fifo.map") + ": is a FIFO"));
  }
}

}  // namespace
}  // namespace fleet::site
