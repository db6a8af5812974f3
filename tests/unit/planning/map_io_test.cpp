#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "fleet/planning/map_io.hpp"
#include "seed_map.hpp"

using namespace fleet;
using namespace fleet::planning;

namespace {
std::string tmpDir() {
  const auto d = std::filesystem::path(FLEET_BINARY_DIR) / "tmp" / "planning_test";
  std::filesystem::create_directories(d);
  return d.string();
}
void writeFile(const std::string& path, const std::string& body) {
  std::ofstream(path, std::ios::binary) << body;
}
}  // namespace

TEST(MovingAi, ParsesAndFlipsRowsToYUp) {
  const auto g = parseMovingAiMap("type octile\nheight 2\nwidth 3\nmap\n@.T\n..G\n", "tiny.map", 0.5, {1, 2});
  ASSERT_TRUE(g.has_value()) << g.error().message;
  EXPECT_EQ(g->width(), 3);
  EXPECT_EQ(g->height(), 2);
  EXPECT_TRUE(g->blocked({0, 1}));  // file row 0 is the top
  EXPECT_FALSE(g->blocked({1, 1}));
  EXPECT_TRUE(g->blocked({2, 1}));
  EXPECT_FALSE(g->blocked({2, 0}));
  EXPECT_DOUBLE_EQ(g->resolution(), 0.5);
  EXPECT_DOUBLE_EQ(g->origin().y, 2.0);
}

TEST(MovingAi, TypeLineIsOptionalAndTerrainFollowsTheMovingAiPage) {
  // Some published maps start at 'height'. Swamp is passable from terrain; water is not.
  const auto g = parseMovingAiMap("height 1\nwidth 5\nmap\n.GSWT\n", "no-type.map");
  ASSERT_TRUE(g.has_value()) << g.error().message;
  EXPECT_FALSE(g->blocked({0, 0}));
  EXPECT_FALSE(g->blocked({1, 0}));
  EXPECT_FALSE(g->blocked({2, 0}));
  EXPECT_TRUE(g->blocked({3, 0}));
  EXPECT_TRUE(g->blocked({4, 0}));
}

TEST(MovingAi, RoundTripThroughAFile) {
  const auto g = parseMovingAiMap(seed004MovingAi(), "seed004");
  ASSERT_TRUE(g.has_value());
  const std::string path = tmpDir() + "/seed004.map";
  ASSERT_TRUE(saveMovingAiMap(*g, path).has_value());
  const auto back = loadMovingAiMap(path);
  ASSERT_TRUE(back.has_value()) << back.error().message;
  EXPECT_EQ(back->cells(), g->cells());
  EXPECT_EQ(g->freeCount(), 115u);
}

TEST(MovingAi, MalformedMapsGiveClearErrors) {
  struct Bad {
    std::string text;
    std::string expect;
  };
  const std::vector<Bad> bad{
      {"type octile\nheight 2\nwidth 3\nmap\n...\n..\n",
       "bad.map:6: row has 2 characters, header says width 3"},
      {"type octile\nheight 2\nwidth 3\nmap\n...\n.x.\n", "bad.map:6: unknown character 'x' at column 2"},
      {"type octile\nheight 3\nwidth 3\nmap\n...\n...\n",
       "truncated map: header says height 3 but only 2 rows"},
      {"type octile\nheight 1\nwidth 3\nmap\n...\n...\n", "bad.map:6: extra rows"},
      {"type octile\nheight -4\nwidth 3\nmap\n", "bad.map:2: height must be a positive integer"},
      {"type octile\nwidth 3\nmap\n...\n", "missing 'height' or 'width'"},
      {"type octile\nheight 1\nwidth 3\n", "missing 'map' line"},
      {"type octile\ncolour 3\n", "bad.map:2: unknown header key 'colour'"},
  };
  for (const auto& b : bad) {
    const auto g = parseMovingAiMap(b.text, "bad.map");
    ASSERT_FALSE(g.has_value()) << b.text;
    EXPECT_EQ(g.error().code, "map_format");
    EXPECT_NE(g.error().message.find(b.expect), std::string::npos) << g.error().message;
  }
  const auto missing = loadMovingAiMap(tmpDir() + "/does-not-exist.map");
  ASSERT_FALSE(missing.has_value());
  EXPECT_NE(missing.error().message.find("does-not-exist.map"), std::string::npos);
}

TEST(ImageMap, PgmWithJsonSideFile) {
  const std::string dir = tmpDir();
  // 4 x 2 image: top row white white black grey, bottom row black white white white.
  std::string pgm = "P5\n# test\n4 2\n255\n";
  for (unsigned char v : {255, 255, 0, 128, 0, 255, 255, 255}) {
    pgm.push_back(static_cast<char>(v));
  }
  writeFile(dir + "/room.pgm", pgm);
  writeFile(dir + "/room.json", R"({"image": "room.pgm", "resolution": 0.05, "origin": [-1.0, 2.0, 0.0],
                                    "occupied_thresh": 0.65, "free_thresh": 0.196, "negate": 0})");
  const auto g = loadImageMap(dir + "/room.json");
  ASSERT_TRUE(g.has_value()) << g.error().message;
  EXPECT_EQ(g->width(), 4);
  EXPECT_EQ(g->height(), 2);
  EXPECT_DOUBLE_EQ(g->resolution(), 0.05);
  EXPECT_DOUBLE_EQ(g->origin().x, -1.0);
  EXPECT_FALSE(g->blocked({0, 1}));
  EXPECT_TRUE(g->blocked({2, 1}));
  EXPECT_TRUE(g->blocked({3, 1}));  // grey = unknown, treated as blocked
  EXPECT_TRUE(g->blocked({0, 0}));
  EXPECT_FALSE(g->blocked({1, 0}));

  writeFile(dir + "/ascii.pgm", "P2\n2 1\n15\n15 0\n");
  const auto a = parsePgm("P2\n2 1\n15\n15 0\n", {}, "ascii.pgm");
  ASSERT_TRUE(a.has_value());
  EXPECT_FALSE(a->blocked({0, 0}));
  EXPECT_TRUE(a->blocked({1, 0}));
}

TEST(ImageMap, MalformedInputsGiveClearErrors) {
  const std::string dir = tmpDir();
  writeFile(dir + "/short.pgm", "P5\n4 4\n255\nab");
  writeFile(dir + "/short.json", R"({"image": "short.pgm", "resolution": 0.1})");
  auto e = loadImageMap(dir + "/short.json");
  ASSERT_FALSE(e.has_value());
  EXPECT_NE(e.error().message.find("short.pgm: truncated PGM data: expected 16 bytes"), std::string::npos)
      << e.error().message;
  writeFile(dir + "/nores.json", R"({"image": "short.pgm"})");
  e = loadImageMap(dir + "/nores.json");
  ASSERT_FALSE(e.has_value());
  EXPECT_NE(e.error().message.find("nores.json: missing key 'resolution'"), std::string::npos);
  writeFile(dir + "/broken.json", R"({"image": )");
  e = loadImageMap(dir + "/broken.json");
  ASSERT_FALSE(e.has_value());
  EXPECT_NE(e.error().message.find("broken.json: invalid JSON"), std::string::npos);
  // A number beyond a double is nlohmann's out_of_range, not parse_error: still an error value.
  writeFile(dir + "/huge.json", R"({"image": "short.pgm", "resolution": 1e999})");
  e = loadImageMap(dir + "/huge.json");
  ASSERT_FALSE(e.has_value());
  EXPECT_NE(e.error().message.find("huge.json: invalid JSON"), std::string::npos);
  writeFile(dir + "/rot.json", R"({"image": "short.pgm", "resolution": 0.1, "origin": [0, 0, 0.3]})");
  e = loadImageMap(dir + "/rot.json");
  ASSERT_FALSE(e.has_value());
  EXPECT_NE(e.error().message.find("yaw must be 0"), std::string::npos);
  e = parsePgm("P6\n1 1\n255\nxxx", {}, "colour.ppm");
  ASSERT_FALSE(e.has_value());
  EXPECT_NE(e.error().message.find("colour.ppm:1: not a PGM image"), std::string::npos);
}
