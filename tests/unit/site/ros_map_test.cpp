// ROS map_server / Nav2 maps: side-file parsing, value interpretation, image decoding, map frame,
// costmap filter masks. Every image is built here, byte by byte (PNG with stored deflate blocks, so
// the encoder shares nothing with libpng), so the repository holds no binary fixtures.

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "fleet/site/ros_map.hpp"

namespace fleet::site {
namespace {

namespace fs = std::filesystem;

// ---------- image writers ----------

std::string pgmP5(int w, int h, const std::vector<int>& v, int maxval = 255) {
  std::string s = "P5\n# CREATOR: map_saver.cpp 0.050 m/pix\n" + std::to_string(w) + " " + std::to_string(h) +
                  "\n" + std::to_string(maxval) + "\n";
  for (int x : v) {
    if (maxval > 255) {
      s += static_cast<char>(x >> 8);
    }
    s += static_cast<char>(x & 0xFF);
  }
  return s;
}

std::string pgmP2(int w, int h, const std::vector<int>& v, int maxval = 255) {
  std::string s = "P2 # ascii\n" + std::to_string(w) + "\n# comment between tokens\n" + std::to_string(h) +
                  " " + std::to_string(maxval) + "\n";
  for (std::size_t k = 0; k < v.size(); ++k) {
    s += std::to_string(v[k]) + ((k + 1) % static_cast<std::size_t>(w) == 0 ? "\n" : " ");
  }
  return s;
}

void be32(std::string& o, std::uint32_t v) {
  for (int sh = 24; sh >= 0; sh -= 8) {
    o += static_cast<char>((v >> sh) & 0xFFU);
  }
}

std::uint32_t crc32(std::string_view s) {
  std::uint32_t c = 0xFFFFFFFFU;
  for (const char ch : s) {
    c ^= static_cast<std::uint8_t>(ch);
    for (int k = 0; k < 8; ++k) {
      c = (c & 1U) != 0 ? 0xEDB88320U ^ (c >> 1) : c >> 1;
    }
  }
  return c ^ 0xFFFFFFFFU;
}

std::string chunk(std::string_view type, const std::string& data) {
  std::string o;
  be32(o, static_cast<std::uint32_t>(data.size()));
  const std::string body = std::string(type) + data;
  o += body;
  be32(o, crc32(body));
  return o;
}

// zlib stream of stored (uncompressed) deflate blocks.
std::string zlibStored(const std::string& raw) {
  std::string o = "\x78\x01";
  std::size_t pos = 0;
  do {
    const std::size_t n = std::min<std::size_t>(65535, raw.size() - pos);
    o += static_cast<char>(pos + n == raw.size() ? 1 : 0);
    o += static_cast<char>(n & 0xFF);
    o += static_cast<char>(n >> 8);
    o += static_cast<char>(~n & 0xFF);
    o += static_cast<char>((~n >> 8) & 0xFF);
    o += raw.substr(pos, n);
    pos += n;
  } while (pos < raw.size());
  std::uint32_t a = 1, b = 0;
  for (const char ch : raw) {
    a = (a + static_cast<std::uint8_t>(ch)) % 65521U;
    b = (b + a) % 65521U;
  }
  be32(o, (b << 16) | a);
  return o;
}

std::string ihdr(std::uint32_t w, std::uint32_t h, int depth, int colourType) {
  std::string d;
  be32(d, w);
  be32(d, h);
  d += static_cast<char>(depth);
  d += static_cast<char>(colourType);
  d += std::string(3, '\0');  // deflate, adaptive filters, no interlace
  return chunk("IHDR", d);
}

// `rows` holds each row's packed bytes; `extra` goes between IHDR and IDAT (PLTE, tRNS).
std::string png(int w, int h, int depth, int colourType, const std::string& rows,
                const std::string& extra = "") {
  const std::size_t rowBytes = rows.size() / static_cast<std::size_t>(h);
  std::string raw;
  for (int y = 0; y < h; ++y) {
    raw += '\0';  // filter: none
    raw += rows.substr(static_cast<std::size_t>(y) * rowBytes, rowBytes);
  }
  return "\x89PNG\r\n\x1a\n" +
         ihdr(static_cast<std::uint32_t>(w), static_cast<std::uint32_t>(h), depth, colourType) + extra +
         chunk("IDAT", zlibStored(raw)) + chunk("IEND", "");
}

std::string bytes(const std::vector<int>& v) {
  std::string s;
  for (int x : v) {
    s += static_cast<char>(x);
  }
  return s;
}

// ---------- helpers ----------

RosMapInfo infoWith(MapMode mode = MapMode::Trinary, bool negate = false) {
  RosMapInfo i;
  i.image = "mem.pgm";
  i.resolution = 1.0;
  i.mode = mode;
  i.negate = negate;
  return i;
}

Image grey(int w, int h, const std::vector<int>& v) {
  Image img{w, h, 1, {}};
  for (int x : v) {
    img.pixels.push_back(static_cast<std::uint8_t>(x));
  }
  return img;
}

// The map value of a single pixel, given as its channel values.
int valueOf(const std::vector<int>& channels, const RosMapInfo& info) {
  Image img{1, 1, static_cast<int>(channels.size()), {}};
  for (int c : channels) {
    img.pixels.push_back(static_cast<std::uint8_t>(c));
  }
  auto m = rosMapFromImage(img, info, "pixel");
  EXPECT_TRUE(m.has_value()) << (m ? "" : m.error().message);
  return m ? m->data[0] : -99;
}

class TempDir {
 public:
  TempDir()
      : path_(fs::temp_directory_path() /
              ("ros_map_test_" + std::to_string(::getpid()) + "_" + std::to_string(counter_++))) {
    fs::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  [[nodiscard]] std::string write(const std::string& name, const std::string& content) const {
    const fs::path p = path_ / name;
    std::ofstream(p, std::ios::binary) << content;
    return p.string();
  }
  [[nodiscard]] const fs::path& path() const { return path_; }

 private:
  static inline int counter_ = 0;
  fs::path path_;
};

const std::string kMapSaverYaml =
    "image: map.pgm\n"
    "mode: trinary\n"
    "resolution: 0.050000\n"
    "origin: [-10.000000, -10.000000, 0.000000]\n"
    "negate: 0\n"
    "occupied_thresh: 0.65\n"
    "free_thresh: 0.25\n"
    "\n";

// ---------- YAML ----------

TEST(RosMapYaml, ReadsMapSaverFile) {
  auto info = parseRosMapYaml(kMapSaverYaml, "map.yaml");
  ASSERT_TRUE(info.has_value()) << info.error().message;
  EXPECT_EQ(info->image, "map.pgm");
  EXPECT_EQ(info->mode, MapMode::Trinary);
  EXPECT_DOUBLE_EQ(info->resolution, 0.05);
  EXPECT_EQ(info->origin, (Pose2{-10.0, -10.0, 0.0}));
  EXPECT_FALSE(info->negate);
  EXPECT_DOUBLE_EQ(info->occupiedThresh, 0.65);
  EXPECT_DOUBLE_EQ(info->freeThresh, 0.25);
}

TEST(RosMapYaml, OptionalKeysAndRos1Style) {
  auto info = parseRosMapYaml("image: /maps/a.png\nresolution: 0.1\norigin: [1, 2.5, 3.5]\n", "a.yaml");
  ASSERT_TRUE(info.has_value()) << info.error().message;
  EXPECT_EQ(info->image, "/maps/a.png");
  EXPECT_EQ(info->mode, MapMode::Trinary);
  EXPECT_FALSE(info->negate);
  EXPECT_DOUBLE_EQ(info->occupiedThresh, 0.65);
  EXPECT_DOUBLE_EQ(info->freeThresh, 0.196);
  EXPECT_NEAR(info->origin.theta, 3.5 - 2 * std::numbers::pi, 1e-12);  // wrapped to (-pi, pi]

  auto old = parseRosMapYaml(
      "image: \"m.pgm\"\nresolution: 0.05\norigin: [0.0, 0.0, 0.0]\nnegate: true\nfree_thresh: 0.196\nmode: "
      "scale\n",
      "old.yaml");
  ASSERT_TRUE(old.has_value()) << old.error().message;
  EXPECT_TRUE(old->negate);
  EXPECT_EQ(old->mode, MapMode::Scale);
  auto raw =
      parseRosMapYaml("{image: r.png, resolution: 1, origin: [0, 0, 0], negate: 1, mode: raw}", "flow.yaml");
  ASSERT_TRUE(raw.has_value()) << raw.error().message;
  EXPECT_TRUE(raw->negate);
  EXPECT_EQ(raw->mode, MapMode::Raw);
}

TEST(RosMapYaml, BadFilesNameTheKey) {
  const std::string ok = "image: map.pgm\nresolution: 0.05\norigin: [0, 0, 0]\n";
  struct Case {
    std::string text;
    std::string mustMention;
  };
  const std::vector<Case> cases = {
      {"resolution: 0.05\norigin: [0, 0, 0]\n", "'image'"},
      {"image: ''\nresolution: 0.05\norigin: [0, 0, 0]\n", "'image'"},
      {"image: [a, b]\nresolution: 0.05\norigin: [0, 0, 0]\n", "'image'"},
      {"image: map.pgm\norigin: [0, 0, 0]\n", "'resolution'"},
      {"image: map.pgm\nresolution: 0\norigin: [0, 0, 0]\n", "'resolution'"},
      {"image: map.pgm\nresolution: -0.05\norigin: [0, 0, 0]\n", "'resolution'"},
      {"image: map.pgm\nresolution: fast\norigin: [0, 0, 0]\n", "'resolution'"},
      {"image: map.pgm\nresolution: .inf\norigin: [0, 0, 0]\n", "'resolution'"},
      {"image: map.pgm\nresolution: 0.05\n", "'origin'"},
      {"image: map.pgm\nresolution: 0.05\norigin: [0, 0]\n", "'origin'"},
      {"image: map.pgm\nresolution: 0.05\norigin: [0, 0, 0, 0]\n", "'origin'"},
      {"image: map.pgm\nresolution: 0.05\norigin: [0, 0, abc]\n", "'origin'"},
      {"image: map.pgm\nresolution: 0.05\norigin: [0, .nan, 0]\n", "'origin'"},
      {"image: map.pgm\nresolution: 0.05\norigin: 3\n", "'origin'"},
      {"image: map.pgm\nresolution:\norigin: [0, 0, 0]\n", "found nothing"},
      {ok + "colour: blue\n", "'colour'"},
      {ok + "mode: foo\n", "'mode'"},
      {ok + "mode: Trinary\n", "'mode'"},
      {ok + "negate: 2\n", "'negate'"},
      {ok + "negate: maybe\n", "'negate'"},
      {ok + "occupied_thresh: 1.5\n", "'occupied_thresh'"},
      {ok + "free_thresh: -0.1\n", "'free_thresh'"},
      {ok + "free_thresh: 0.7\n", "'free_thresh'"},  // >= occupied (0.65)
      {ok + "free_thresh: 0.5\noccupied_thresh: 0.5\n", "'free_thresh'"},
      {ok + "resolution: 0.1\n", "'resolution'"},  // repeated
  };
  for (const auto& c : cases) {
    auto r = parseRosMapYaml(c.text, "site/map.yaml");
    ASSERT_FALSE(r.has_value()) << c.text;
    EXPECT_EQ(r.error().code, "map_yaml") << c.text;
    EXPECT_NE(r.error().message.find("site/map.yaml"), std::string::npos) << r.error().message;
    EXPECT_NE(r.error().message.find(c.mustMention), std::string::npos)
        << c.text << " -> " << r.error().message;
  }
}

TEST(RosMapYaml, NotAMappingIsAnErrorNotAnException) {
  for (const std::string& text :
       {std::string("P5\n3 2\n255\n\x01\x02\x03", 14), std::string("- image: a.pgm\n- b\n"), std::string(""),
        std::string("image: [unclosed\n"), std::string("{{{{: :"), std::string("\t\x01\xff\xfe binary")}) {
    auto r = parseRosMapYaml(text, "bad.yaml");
    ASSERT_FALSE(r.has_value()) << text;
    EXPECT_EQ(r.error().code, "map_yaml");
    EXPECT_EQ(r.error().message.rfind("bad.yaml", 0), 0U) << r.error().message;
  }
  auto list = parseRosMapYaml("- image: a.pgm\n- resolution: 1\n", "l.yaml");
  ASSERT_FALSE(list.has_value());
  EXPECT_NE(list.error().message.find("list"), std::string::npos) << list.error().message;
}

// ---------- value interpretation ----------

TEST(RosMapValues, TrinaryMapSaverGreys) {
  const RosMapInfo i = infoWith();  // occupied 0.65, free 0.196
  EXPECT_EQ(valueOf({0}, i), 100);
  EXPECT_EQ(valueOf({255}, i), 0);
  EXPECT_EQ(valueOf({254}, i), 0);   // map_saver's free
  EXPECT_EQ(valueOf({205}, i), -1);  // map_saver's unknown: occ = 50/255 = 0.19608 > 0.196
  EXPECT_EQ(valueOf({206}, i), 0);   // occ = 0.19216
  EXPECT_EQ(valueOf({89}, i), 100);  // occ = 0.65098
  EXPECT_EQ(valueOf({90}, i), -1);   // occ = 0.64706
  EXPECT_EQ(valueOf({128}, i), -1);
}

TEST(RosMapValues, MapSaverUnknownStaysUnknownWithNav2Thresholds) {
  RosMapInfo i = infoWith();
  i.freeThresh = 0.25;  // what Nav2's map_saver writes; Nav2 itself would read 205 as free
  EXPECT_EQ(valueOf({205}, i), -1);
  EXPECT_EQ(valueOf({205, 205, 205}, i), -1);
  EXPECT_EQ(valueOf({204}, i), 0);  // occ 0.2: only map_saver's own code is special
  EXPECT_EQ(valueOf({206}, i), 0);
  EXPECT_EQ(valueOf({254}, i), 0);
  i.mode = MapMode::Scale;  // scale maps encode values as greys: 205 is a real value there
  EXPECT_EQ(valueOf({205}, i), 0);
}

TEST(RosMapValues, ThresholdsAreStrict) {
  RosMapInfo i = infoWith();
  i.occupiedThresh = 0.6;  // pixel 102: occ = 153/255 = 0.6 exactly
  i.freeThresh = 0.2;      // pixel 204: occ = 51/255 = 0.2 exactly
  EXPECT_EQ(valueOf({101}, i), 100);
  EXPECT_EQ(valueOf({102}, i), -1);
  EXPECT_EQ(valueOf({204}, i), -1);
  EXPECT_EQ(valueOf({206}, i), 0);  // (205 is map_saver's unknown, see above)
}

TEST(RosMapValues, Negate) {
  const RosMapInfo i = infoWith(MapMode::Trinary, true);
  EXPECT_EQ(valueOf({0}, i), 0);
  EXPECT_EQ(valueOf({255}, i), 100);
  EXPECT_EQ(valueOf({50}, i), -1);    // occ = 50/255 = 0.19608
  EXPECT_EQ(valueOf({49}, i), 0);     // occ = 0.19216
  EXPECT_EQ(valueOf({205}, i), 100);  // occ = 0.80392
  EXPECT_EQ(valueOf({166}, i), 100);  // occ = 0.65098
}

TEST(RosMapValues, Scale) {
  const RosMapInfo i = infoWith(MapMode::Scale);
  EXPECT_EQ(valueOf({0}, i), 100);
  EXPECT_EQ(valueOf({255}, i), 0);
  // occ = 127/255 = 0.498039; (0.498039 - 0.196) / (0.65 - 0.196) * 100 = 66.53 -> 67
  EXPECT_EQ(valueOf({128}, i), 67);
  // occ = 50/255 = 0.196078; (0.000078 / 0.454) * 100 = 0.017 -> 0: in between, but rounds to free
  EXPECT_EQ(valueOf({205}, i), 0);
  // occ = 0.647059 -> 99.35 -> 99
  EXPECT_EQ(valueOf({90}, i), 99);
  // Any transparency is unknown in scale mode; opaque pixels are read normally.
  EXPECT_EQ(valueOf({128, 255}, i), 67);
  EXPECT_EQ(valueOf({128, 254}, i), -1);
  EXPECT_EQ(valueOf({0, 0, 0, 0}, i), -1);
  EXPECT_EQ(valueOf({255, 255, 255, 255}, i), 0);
}

TEST(RosMapValues, RawIgnoresNegateAndAlpha) {
  for (const bool negate : {false, true}) {
    const RosMapInfo i = infoWith(MapMode::Raw, negate);
    EXPECT_EQ(valueOf({0}, i), 0);
    EXPECT_EQ(valueOf({37}, i), 37);
    EXPECT_EQ(valueOf({100}, i), 100);
    EXPECT_EQ(valueOf({101}, i), -1);
    EXPECT_EQ(valueOf({255}, i), -1);
    EXPECT_EQ(valueOf({37, 0}, i), 37);
    EXPECT_EQ(valueOf({10, 20, 31}, i), 20);  // mean 20.33 -> 20
    EXPECT_EQ(valueOf({10, 20, 31, 0}, i), 20);
    EXPECT_EQ(valueOf({10, 21, 31}, i), 21);  // mean 20.67 -> 21
  }
}

TEST(RosMapValues, ColourAndAlphaInTrinary) {
  const RosMapInfo i = infoWith();
  EXPECT_EQ(valueOf({255, 0, 0}, i), 100);    // mean 85, occ 0.667
  EXPECT_EQ(valueOf({255, 255, 0}, i), -1);   // mean 170, occ 0.333
  EXPECT_EQ(valueOf({200, 210, 220}, i), 0);  // mean 210, occ 0.176
  // Trinary averages alpha in as a fourth channel (Nav2, ROS 1).
  EXPECT_EQ(valueOf({255, 255}, i), 0);
  EXPECT_EQ(valueOf({255, 0}, i), -1);  // (3 * 255 + 0) / 4 = 191.25, occ 0.25
  EXPECT_EQ(valueOf({255, 255, 255, 0}, i), -1);
  EXPECT_EQ(valueOf({0, 255}, i), 100);            // 63.75, occ 0.75
  EXPECT_EQ(valueOf({255, 255, 255, 200}, i), 0);  // 241.25, occ 0.054
}

TEST(RosMapValues, RowsAreStoredBottomUp) {
  // 2 x 3 image, rows top to bottom: [0 255] [255 255] [255 205]
  auto m = rosMapFromImage(grey(2, 3, {0, 255, 255, 255, 255, 205}), infoWith(), "mem");
  ASSERT_TRUE(m.has_value());
  EXPECT_EQ(m->data, (std::vector<std::int8_t>{0, -1, 0, 0, 100, 0}));
}

TEST(RosMapValues, InconsistentImageOrInfoIsAnError) {
  Image bad = grey(2, 2, {0, 0, 0});
  auto r = rosMapFromImage(bad, infoWith(), "bad.png");
  ASSERT_FALSE(r.has_value());
  EXPECT_EQ(r.error().code, "map_image");
  RosMapInfo i = infoWith();
  i.resolution = 0.0;
  auto r2 = rosMapFromImage(grey(1, 1, {0}), i, "mask");
  ASSERT_FALSE(r2.has_value());
  EXPECT_NE(r2.error().message.find("'resolution'"), std::string::npos);
}

// ---------- decoding ----------

// 4 x 3 map: occupied, free, unknown and in-between greys.
const std::vector<int> kGreys = {0, 254, 254, 205, 254, 0, 128, 254, 205, 205, 254, 90};

std::vector<std::int8_t> mapOf(const std::string& file, const std::string& name,
                               MapMode mode = MapMode::Trinary) {
  auto img = decodeImage(file, name);
  EXPECT_TRUE(img.has_value()) << name << ": " << (img ? "" : img.error().message);
  if (!img) {
    return {};
  }
  EXPECT_EQ(img->width, 4) << name;
  EXPECT_EQ(img->height, 3) << name;
  auto m = rosMapFromImage(*img, infoWith(mode), name);
  EXPECT_TRUE(m.has_value()) << name;
  return m ? m->data : std::vector<std::int8_t>{};
}

TEST(ImageDecode, EveryFormatGivesTheSameMap) {
  const auto expected = mapOf(pgmP5(4, 3, kGreys), "p5.pgm");
  ASSERT_EQ(expected, (std::vector<std::int8_t>{-1, -1, 0, -1, 0, 100, -1, 0, 100, 0, 0, -1}));

  std::vector<int> wide;
  std::string grey16, rgb, palette, paletteIdx;
  for (int v : kGreys) {
    wide.push_back(v * 257);
    grey16 += bytes({v, v});  // v * 257 big endian
    rgb += bytes({v, v, v});
  }
  const std::vector<int> levels = {0, 90, 128, 205, 254};
  for (int v : levels) {
    palette += bytes({v, v, v});
  }
  for (int v : kGreys) {
    paletteIdx += static_cast<char>(std::find(levels.begin(), levels.end(), v) - levels.begin());
  }
  EXPECT_EQ(mapOf(pgmP2(4, 3, kGreys), "p2.pgm"), expected);
  EXPECT_EQ(mapOf(pgmP5(4, 3, wide, 65535), "p5-16.pgm"), expected);
  EXPECT_EQ(mapOf(pgmP2(4, 3, wide, 65535), "p2-16.pgm"), expected);
  EXPECT_EQ(mapOf(png(4, 3, 8, 0, bytes(kGreys)), "grey.png"), expected);
  EXPECT_EQ(mapOf(png(4, 3, 16, 0, grey16), "grey16.png"), expected);
  EXPECT_EQ(mapOf(png(4, 3, 8, 2, rgb), "rgb.png"), expected);
  EXPECT_EQ(mapOf(png(4, 3, 8, 3, paletteIdx, chunk("PLTE", palette)), "palette.png"), expected);

  // With alpha the trinary mean includes alpha, so compare in scale mode where opaque alpha is neutral.
  const auto scaled = mapOf(pgmP5(4, 3, kGreys), "p5.pgm", MapMode::Scale);
  std::string ga, rgba;
  for (int v : kGreys) {
    ga += bytes({v, 255});
    rgba += bytes({v, v, v, 255});
  }
  EXPECT_EQ(mapOf(png(4, 3, 8, 4, ga), "ga.png", MapMode::Scale), scaled);
  EXPECT_EQ(mapOf(png(4, 3, 8, 6, rgba), "rgba.png", MapMode::Scale), scaled);
  EXPECT_EQ(mapOf(png(4, 3, 8, 3, paletteIdx, chunk("PLTE", palette) + chunk("tRNS", bytes({255, 255}))),
                  "palette-trns.png", MapMode::Scale),
            scaled);
}

TEST(ImageDecode, ChannelsAndSampleScaling) {
  // RGBA with a transparent pixel keeps its alpha; 16-bit samples are rounded, not truncated.
  auto rgba = decodeImage(png(2, 1, 8, 6, bytes({10, 20, 30, 0, 40, 50, 60, 255})), "rgba.png");
  ASSERT_TRUE(rgba.has_value()) << rgba.error().message;
  EXPECT_EQ(rgba->channels, 4);
  EXPECT_EQ(rgba->pixels, (std::vector<std::uint8_t>{10, 20, 30, 0, 40, 50, 60, 255}));
  auto scale = rosMapFromImage(*rgba, infoWith(MapMode::Scale), "rgba.png");
  ASSERT_TRUE(scale.has_value());
  EXPECT_EQ(scale->data[0], -1);   // alpha 0
  EXPECT_EQ(scale->data[1], 100);  // mean 50, occ 0.80

  // 511 / 65535 * 255 = 1.99 -> 2 (the high byte would say 1); 15-level PGM: 7 / 15 * 255 = 119.
  auto g16 = decodeImage(png(2, 1, 16, 0, bytes({0x01, 0xFF, 0xFF, 0xFF})), "g16.png");
  ASSERT_TRUE(g16.has_value()) << g16.error().message;
  EXPECT_EQ(g16->pixels, (std::vector<std::uint8_t>{2, 255}));
  auto p16 = decodeImage(pgmP5(2, 1, {0x01FF, 0xFFFF}, 65535), "p16.pgm");
  ASSERT_TRUE(p16.has_value());
  EXPECT_EQ(p16->pixels, g16->pixels);
  auto p15 = decodeImage(pgmP2(3, 1, {0, 7, 15}, 15), "p15.pgm");
  ASSERT_TRUE(p15.has_value());
  EXPECT_EQ(p15->pixels, (std::vector<std::uint8_t>{0, 119, 255}));

  // 1-bit grey expands to 0 / 255; grey + tRNS gains an alpha channel.
  auto bit = decodeImage(png(3, 1, 1, 0, bytes({0b10100000})), "bit.png");
  ASSERT_TRUE(bit.has_value()) << bit.error().message;
  EXPECT_EQ(bit->pixels, (std::vector<std::uint8_t>{255, 0, 255}));
  auto trns = decodeImage(png(2, 1, 8, 0, bytes({7, 9}), chunk("tRNS", bytes({0, 7}))), "trns.png");
  ASSERT_TRUE(trns.has_value()) << trns.error().message;
  EXPECT_EQ(trns->channels, 2);
  EXPECT_EQ(trns->pixels, (std::vector<std::uint8_t>{7, 0, 9, 255}));
}

void expectImageError(const std::string& file, const std::string& name, const std::string& mention = "") {
  auto r = decodeImage(file, name);
  ASSERT_FALSE(r.has_value()) << name;
  EXPECT_EQ(r.error().code, "map_image") << name;
  EXPECT_EQ(r.error().message.rfind(name + ": ", 0), 0U) << r.error().message;
  if (!mention.empty()) {
    EXPECT_NE(r.error().message.find(mention), std::string::npos) << r.error().message;
  }
}

TEST(ImageDecode, CorruptPgm) {
  const std::string good = pgmP5(4, 3, kGreys);
  expectImageError(good.substr(0, good.size() - 1), "short.pgm", "shorter than the header says");
  const std::string good16 = pgmP5(4, 3, kGreys, 65535);
  expectImageError(good16.substr(0, good16.size() - 3), "short16.pgm", "shorter");
  expectImageError("P5\n0 3\n255\n", "zero.pgm", "zero width");
  expectImageError("P5\n100000 100000\n255\n\x01\x02", "huge.pgm", "67108864 = 2^26");
  expectImageError("P5\n8000 8000\n255\n\x01\x02", "big.pgm", "shorter");
  expectImageError("P5\n2 1\n100\n\x01\xC8", "over.pgm", "exceeds maxval");
  expectImageError("P5\n2 1\n70000\n", "maxval.pgm", "maxval");
  expectImageError("P5\n2 x\n255\n", "header.pgm", "header");
  expectImageError("P2\n2 2\n255\n1 2 3\n", "short.pgm", "ends");
  expectImageError("P2\n2 2\n255\n1 2 3 x 5 6 7 8 9\n", "junk.pgm", "not a number");
  expectImageError("P2\n2 1\n255\n1 99999999999\n", "long.pgm");
  expectImageError("P6\n1 1\n255\n\x01\x02\x03", "colour.ppm", "magic");
  expectImageError("GIF89a....", "map.gif", "magic");
  expectImageError("", "empty.pgm", "empty");
}

TEST(ImageDecode, CorruptPng) {
  const std::string good = png(4, 3, 8, 0, bytes(kGreys));
  ASSERT_TRUE(decodeImage(good, "good.png").has_value());
  const std::size_t idat = good.find("IDAT");

  const std::size_t idatLength = (static_cast<std::size_t>(static_cast<std::uint8_t>(good[idat - 2])) << 8) |
                                 static_cast<std::uint8_t>(good[idat - 1]);
  std::string badCrc = good;
  badCrc[idat + 4 + idatLength] ^= 0x40;  // the CRC itself
  expectImageError(badCrc, "crc.png", "CRC");
  std::string badPixel = good;
  badPixel[idat + 4 + 2 + 5 + 2] ^= 0x40;  // a pixel byte (after zlib, stored-block and filter headers)
  expectImageError(badPixel, "pixel.png", "IDAT");  // zlib's Adler-32 notices before the CRC
  std::string badZlib = good;
  badZlib[idat + 4 + 2 + 3] ^= 0x40;  // the stored block's length check
  expectImageError(badZlib, "zlib.png", "IDAT");

  expectImageError(good.substr(0, idat + 20), "cut.png", "truncated");
  expectImageError(good.substr(0, good.size() - 12), "noend.png", "truncated");

  // A complete, correctly checksummed IDAT that holds only half the rows.
  std::string half = "\x89PNG\r\n\x1a\n" + ihdr(4, 3, 8, 0) +
                     chunk("IDAT", zlibStored(std::string("\0", 1) + bytes({0, 254, 254, 205}))) +
                     chunk("IEND", "");
  expectImageError(half, "half.png");

  const std::string tiny = chunk("IDAT", zlibStored(std::string(10, '\0'))) + chunk("IEND", "");
  expectImageError("\x89PNG\r\n\x1a\n" + ihdr(8000, 8000, 8, 0) + tiny, "big.png", "shorter");
  expectImageError("\x89PNG\r\n\x1a\n" + ihdr(50000, 50000, 8, 0) + tiny, "huge.png", "67108864 = 2^26");
  expectImageError("\x89PNG\r\n\x1a\n" + ihdr(0, 3, 8, 0) + tiny, "zero.png", "corrupt PNG");
  expectImageError("\x89PNG\r\n\x1a\n" + ihdr(4, 3, 7, 0) + tiny, "depth.png", "corrupt PNG");
  expectImageError(good.substr(0, 8), "magic-only.png", "corrupt PNG");
}

// Every prefix and a few thousand random byte changes of valid files: an error or an image, never a
// crash, a hang or (under the sanitizer build) a leak.
TEST(ImageDecode, FuzzedInputsNeverCrash) {
  std::string rgb;
  for (int v : kGreys) {
    rgb += bytes({v, 255 - v, v / 2});
  }
  const std::vector<std::string> seeds = {
      png(4, 3, 8, 2, rgb), png(4, 3, 16, 0, bytes(kGreys) + bytes(kGreys)), pgmP5(4, 3, kGreys),
      pgmP2(4, 3, kGreys), pgmP5(4, 3, kGreys, 4095)};
  std::mt19937 rng(7);
  int decoded = 0;
  for (const auto& seed : seeds) {
    for (std::size_t n = 0; n < seed.size(); ++n) {
      decoded += decodeImage(seed.substr(0, n), "prefix").has_value() ? 1 : 0;
    }
    for (int trial = 0; trial < 1000; ++trial) {
      std::string s = seed;
      for (int k = 0; k < 1 + trial % 4; ++k) {
        s[rng() % s.size()] = static_cast<char>(rng());
      }
      if (auto img = decodeImage(s, "fuzz")) {
        ++decoded;
        EXPECT_EQ(img->pixels.size(), static_cast<std::size_t>(img->width) *
                                          static_cast<std::size_t>(img->height) *
                                          static_cast<std::size_t>(img->channels));
      }
    }
  }
  EXPECT_GT(decoded, 0);  // some changes hit pixel values only
}

// ---------- map frame ----------

TEST(RosMapFrame, TopLeftPixelIsHighestRow) {
  // 3 x 2 image, black pixel top-left, origin (1, 2), 0.5 m pixels.
  RosMapInfo info = infoWith();
  info.resolution = 0.5;
  info.origin = {1.0, 2.0, 0.0};
  auto m = rosMapFromImage(grey(3, 2, {0, 254, 254, 254, 254, 254}), info, "mem");
  ASSERT_TRUE(m.has_value());
  const auto g = toOccupancyGrid(*m);
  ASSERT_EQ(g.width(), 3);
  ASSERT_EQ(g.height(), 2);
  EXPECT_DOUBLE_EQ(g.resolution(), 0.5);
  EXPECT_EQ(g.origin(), (Vec2{1.0, 2.0}));
  for (int y = 0; y < 2; ++y) {
    for (int x = 0; x < 3; ++x) {
      EXPECT_EQ(g.blocked({x, y}), x == 0 && y == 1) << x << "," << y;
    }
  }
  EXPECT_EQ(g.cellCenter({0, 1}), (Vec2{1.25, 2.75}));
  EXPECT_EQ(valueAt(*m, {1.25, 2.75}), 100);
  EXPECT_EQ(valueAt(*m, {1.0, 2.5}), 100);  // lower-left corner of that pixel
  EXPECT_EQ(valueAt(*m, {1.25, 2.49}), 0);
  EXPECT_EQ(valueAt(*m, {2.49, 2.99}), 0);
  EXPECT_EQ(valueAt(*m, {0.99, 2.75}), -1);  // off the image
  EXPECT_EQ(valueAt(*m, {1.25, 3.0}), -1);
  EXPECT_EQ(valueAt(*m, {2.5, 2.25}), -1);
  EXPECT_EQ(valueAt(*m, {std::numeric_limits<double>::quiet_NaN(), 2.25}), -1);
}

TEST(RosMapFrame, MapSaverMapLoadsExactly) {
  TempDir dir;
  // 5 x 4 map_saver map: 254 free, 0 occupied, 205 unknown.
  const std::vector<int> px = {205, 205, 0,   0,   205, 205, 254, 254, 254, 0,
                               0,   254, 254, 254, 0,   205, 0,   0,   0,   205};
  (void)dir.write("map.pgm", pgmP5(5, 4, px));
  const std::string yaml = dir.write("map.yaml", kMapSaverYaml);
  auto m = loadRosMap(yaml);
  ASSERT_TRUE(m.has_value()) << m.error().message;
  EXPECT_EQ(m->width, 5);
  EXPECT_EQ(m->height, 4);
  const auto g = toOccupancyGrid(*m);
  EXPECT_EQ(g.origin(), (Vec2{-10.0, -10.0}));
  EXPECT_DOUBLE_EQ(g.resolution(), 0.05);
  for (int row = 0; row < 4; ++row) {
    for (int x = 0; x < 5; ++x) {
      EXPECT_EQ(g.freeCell({x, 3 - row}), px[static_cast<std::size_t>(row * 5 + x)] == 254)
          << x << "," << row;
    }
  }
  EXPECT_EQ(g.freeCount(), 6U);

  // Absolute image path, PNG under a .pgm name (format by magic bytes).
  const std::string pngPath = dir.write("elsewhere.pgm", png(5, 4, 8, 0, bytes(px)));
  const std::string yaml2 =
      dir.write("abs.yaml", "image: " + pngPath + "\nresolution: 0.05\norigin: [0, 0, 0]\n");
  auto m2 = loadRosMap(yaml2);
  ASSERT_TRUE(m2.has_value()) << m2.error().message;
  EXPECT_EQ(m2->data, m->data);

  const std::string missing =
      dir.write("missing.yaml", "image: nope.pgm\nresolution: 0.05\norigin: [0, 0, 0]\n");
  auto e = loadRosMap(missing);
  ASSERT_FALSE(e.has_value());
  EXPECT_EQ(e.error().code, "map_image");
  EXPECT_NE(e.error().message.find("nope.pgm"), std::string::npos) << e.error().message;
  auto e2 = loadRosMap((dir.path() / "no.yaml").string());
  ASSERT_FALSE(e2.has_value());
  EXPECT_EQ(e2.error().code, "map_yaml");
  const std::string broken =
      dir.write("broken.yaml", "image: bad.pgm\nresolution: 0.05\norigin: [0, 0, 0]\n");
  (void)dir.write("bad.pgm", "P5\n5 4\n255\n\x01");
  auto e3 = loadRosMap(broken);
  ASSERT_FALSE(e3.has_value());
  EXPECT_EQ(e3.error().code, "map_image");
  EXPECT_NE(e3.error().message.find("bad.pgm"), std::string::npos);
}

TEST(RosMapFrame, QuarterTurnYaw) {
  // Same 3 x 2 image turned a quarter turn counter-clockwise about the origin (1, 2): the image's x
  // axis points up, its y axis left. Bounding box x in [0, 1], y in [2, 3.5].
  RosMapInfo info = infoWith();
  info.resolution = 0.5;
  info.origin = {1.0, 2.0, std::numbers::pi / 2};
  auto m = rosMapFromImage(grey(3, 2, {0, 254, 254, 254, 254, 254}), info, "mem");
  ASSERT_TRUE(m.has_value());
  // Top-left pixel: column 0, ROS row 1; its centre (0.25, 0.75) in the image frame -> (1 - 0.75, 2 + 0.25).
  EXPECT_EQ(valueAt(*m, {0.25, 2.25}), 100);
  EXPECT_EQ(valueAt(*m, {0.75, 2.25}), 0);   // column 0, row 0
  EXPECT_EQ(valueAt(*m, {0.25, 3.25}), 0);   // column 2, row 1
  EXPECT_EQ(valueAt(*m, {1.25, 2.25}), -1);  // right of the origin is off the image now
  const auto g = toOccupancyGrid(*m);
  ASSERT_EQ(g.width(), 2);
  ASSERT_EQ(g.height(), 3);
  EXPECT_NEAR(g.origin().x, 0.0, 1e-12);
  EXPECT_NEAR(g.origin().y, 2.0, 1e-12);
  for (std::size_t k = 0; k < g.size(); ++k) {
    EXPECT_EQ(g.blocked(g.cellOf(k)), k == 0) << k;
  }
}

TEST(RosMapFrame, RotatedGridAgreesWithValueAt) {
  std::mt19937 rng(3);
  Image img = grey(23, 17, {});
  for (int k = 0; k < 23 * 17; ++k) {
    img.pixels.push_back(static_cast<std::uint8_t>(std::array{0, 205, 254, 254}[rng() % 4]));
  }
  for (const double yaw : {0.0, 0.3, std::numbers::pi / 2, 2.0, -2.5, std::numbers::pi}) {
    RosMapInfo info = infoWith();
    info.resolution = 0.1;
    info.origin = {-1.3, 0.7, yaw};
    auto m = rosMapFromImage(img, info, "mem");
    ASSERT_TRUE(m.has_value());
    const auto g = toOccupancyGrid(*m);
    // Every cell samples the pixel under its centre; free only on free pixels.
    for (std::size_t k = 0; k < g.size(); ++k) {
      const auto c = g.cellOf(k);
      ASSERT_EQ(g.blocked(c), valueAt(*m, g.cellCenter(c)) != 0) << yaw << " " << k;
    }
    // The grid covers every pixel: each pixel centre, placed by hand, is inside it and reads back.
    const double cs = std::cos(yaw), sn = std::sin(yaw);
    for (int j = 0; j < 17; ++j) {
      for (int i = 0; i < 23; ++i) {
        const double u = (i + 0.5) * 0.1, v = (j + 0.5) * 0.1;
        const Vec2 p{-1.3 + cs * u - sn * v, 0.7 + sn * u + cs * v};
        ASSERT_TRUE(g.cellAt(p).has_value()) << yaw;
        EXPECT_EQ(valueAt(*m, p), m->data[static_cast<std::size_t>(j * 23 + i)]) << yaw;
      }
    }
    const double area = std::abs(cs) * 2.3 + std::abs(sn) * 1.7;
    EXPECT_LE(g.width(), static_cast<int>(std::ceil(area / 0.1 - 1e-6))) << yaw;
    if (yaw == 0.0) {
      EXPECT_EQ(g.width(), 23);
      EXPECT_EQ(g.height(), 17);
      EXPECT_EQ(g.origin(), (Vec2{-1.3, 0.7}));
    }
  }
}

// ---------- costmap filter masks ----------

// 4 x 4 mask of 1 m pixels at (0, 0); rows top to bottom.
RosMap mask(const std::vector<int>& px, MapMode mode, Pose2 origin = {}) {
  RosMapInfo info = infoWith(mode);
  info.origin = origin;
  auto m = rosMapFromImage(grey(4, 4, px), info, "mask");
  EXPECT_TRUE(m.has_value());
  return *m;
}

TEST(NavMask, KeepoutAtAnotherResolution) {
  const RosMap k = mask({254, 254, 0, 0,      //
                         254, 205, 0, 0,      //
                         254, 254, 254, 254,  //
                         128, 254, 254, 254},
                        MapMode::Trinary);
  // Site of 0.5 m cells from (0, 0) to (5, 5): every mask pixel covers 2 x 2 site cells.
  const planning::OccupancyGrid site(10, 10, 0.5);
  std::vector<std::size_t> expected;
  for (int y = 6; y < 8; ++y) {  // mask rows 0-1 (top) are map y in [2, 4) -> site rows 4..7
    for (int x = 4; x < 8; ++x) {
      expected.push_back(site.index({x, y}));
    }
  }
  for (int y = 4; y < 6; ++y) {
    for (int x = 4; x < 8; ++x) {
      expected.push_back(site.index({x, y}));
    }
  }
  std::sort(expected.begin(), expected.end());
  EXPECT_EQ(keepoutCells(k, site), expected);  // not the unknown pixel, not the 128 one, nothing off the mask

  // Scale-mode mask: only 100 is lethal for Nav2; intermediate values are costs.
  const RosMap s =
      mask({0, 150, 254, 254, 254, 254, 254, 254, 254, 254, 254, 254, 254, 254, 254, 254}, MapMode::Scale);
  ASSERT_EQ(s.data[12], 100);
  ASSERT_GT(s.data[13], 0);
  ASSERT_LT(s.data[13], 100);
  const planning::OccupancyGrid coarse(2, 2, 2.0, {0.5, 2.5});  // centre (1.5, 3.5): the 150 pixel
  EXPECT_EQ(keepoutCells(s, coarse), (std::vector<std::size_t>{}));
  const planning::OccupancyGrid fine(1, 1, 0.2, {0.4, 3.4});  // centre (0.5, 3.5): mask pixel (0, 3)
  EXPECT_EQ(keepoutCells(s, fine), (std::vector<std::size_t>{0}));
}

TEST(NavMask, SpeedLimits) {
  // Raw mask: the pixel value is the mask value. Rows top to bottom.
  const RosMap r = mask({0, 20, 50, 205,  //
                         0, 0, 0, 0,      //
                         0, 0, 0, 0,      //
                         100, 0, 0, 0},
                        MapMode::Raw, {10.0, 0.0, 0.0});
  // Site of 1 m cells from (10, 0), one column wider than the mask: cell (x, y) is mask pixel (x, y).
  const planning::OccupancyGrid site(5, 4, 1.0, {10.0, 0.0});
  const std::size_t c20 = site.index({1, 3}), c50 = site.index({2, 3}), c100 = site.index({0, 0});
  auto limits = [&](SpeedMaskType t, double base, double mult) {
    std::vector<std::pair<std::size_t, double>> out;
    for (const auto& s : speedCells(r, site, t, base, mult, 2.0)) {
      out.emplace_back(s.cell, s.limit);
    }
    return out;
  };
  using V = std::vector<std::pair<std::size_t, double>>;
  // Percent of 2 m/s: 20 % -> 0.4, 50 % -> 1.0, 100 % limits nothing. Unknown (205) and off-mask: none.
  const auto pct = limits(SpeedMaskType::Percent, 0.0, 1.0);
  ASSERT_EQ(pct.size(), 2U);
  EXPECT_EQ(pct[0].first, c20);
  EXPECT_DOUBLE_EQ(pct[0].second, 0.4);
  EXPECT_EQ(pct[1].first, c50);
  EXPECT_DOUBLE_EQ(pct[1].second, 1.0);
  // 100 - v: 80 % -> 1.6, 50 % -> 1.0, v = 100 gives 0 % = Nav2's "no limit".
  const auto inv = limits(SpeedMaskType::Percent, 100.0, -1.0);
  ASSERT_EQ(inv.size(), 2U);
  EXPECT_DOUBLE_EQ(inv[0].second, 1.6);
  EXPECT_DOUBLE_EQ(inv[1].second, 1.0);
  // Mask value 0 is "no limit" whatever the base: 10 + v gives 30 % and 60 %, and 110 % (ignored).
  EXPECT_EQ(limits(SpeedMaskType::Percent, 10.0, 1.0), (V{{c20, 0.6}, {c50, 1.2}}));
  // 3 v: 60 % -> 1.2; 150 % and 300 % are out of [0, 100] and ignored.
  EXPECT_EQ(limits(SpeedMaskType::Percent, 0.0, 3.0), (V{{c20, 1.2}}));
  // Absolute: 0.01 v m/s -> 0.2, 0.5, 1.0.
  const auto abs = limits(SpeedMaskType::Absolute, 0.0, 0.01);
  ASSERT_EQ(abs.size(), 3U);
  EXPECT_EQ(abs[0].first, c100);
  EXPECT_DOUBLE_EQ(abs[0].second, 1.0);
  EXPECT_DOUBLE_EQ(abs[1].second, 0.2);
  EXPECT_DOUBLE_EQ(abs[2].second, 0.5);
  // -0.3 + 0.01 v: v = 20 gives -0.1 (no limit), 50 gives 0.2, 100 gives 0.7.
  const auto neg = limits(SpeedMaskType::Absolute, -0.3, 0.01);
  ASSERT_EQ(neg.size(), 2U);
  EXPECT_EQ(neg[0].first, c100);
  EXPECT_NEAR(neg[0].second, 0.7, 1e-12);
  EXPECT_EQ(neg[1].first, c50);
  EXPECT_NEAR(neg[1].second, 0.2, 1e-12);
  // Above the top speed: not a limit.
  EXPECT_EQ(limits(SpeedMaskType::Absolute, 0.0, 0.05), (V{{c20, 1.0}}));
}

TEST(NavMask, SpeedMaskAsInTheNav2Tutorial) {
  // Nav2's speed mask tutorial: mode scale, free_thresh 0, occupied_thresh 1, so value =
  // rint(100 * (255 - grey) / 255). Grey 204 -> 20, 127 -> 50. Mask of 0.25 m pixels, site of 1 m.
  RosMapInfo info = infoWith(MapMode::Scale);
  info.freeThresh = 0.0;
  info.occupiedThresh = 1.0;
  info.resolution = 0.25;
  std::vector<int> px(64, 255);
  px[7 * 8 + 1] = 204;  // bottom row, column 1: x in [0.25, 0.5), y in [0, 0.25)
  px[3 * 8 + 6] = 127;  // row 4 from the bottom, column 6: x in [1.5, 1.75), y in [1, 1.25)
  auto m = rosMapFromImage(grey(8, 8, px), info, "speed_mask");
  ASSERT_TRUE(m.has_value());
  EXPECT_EQ(valueAt(*m, {0.3, 0.1}), 20);
  EXPECT_EQ(valueAt(*m, {1.6, 1.1}), 50);
  // Site cells of 1 m sample centres (0.5, 0.5), (1.5, 0.5), (0.5, 1.5), (1.5, 1.5): none hits a slow
  // pixel, so nothing is limited; shift the site so that centres land on them.
  EXPECT_TRUE(speedCells(*m, planning::OccupancyGrid(2, 2, 1.0), SpeedMaskType::Percent, 0, 1, 1.0).empty());
  const planning::OccupancyGrid site(2, 2, 1.0, {-0.15, -0.4});  // centres (0.35, 0.1), (1.35, 0.1), ...
  const auto s = speedCells(*m, site, SpeedMaskType::Percent, 0.0, 1.0, 1.5);
  ASSERT_EQ(s.size(), 1U);
  EXPECT_EQ(s[0].cell, 0U);
  EXPECT_DOUBLE_EQ(s[0].limit, 0.3);                           // 20 % of 1.5 m/s
  const planning::OccupancyGrid site2(1, 1, 1.0, {1.1, 0.6});  // centre (1.6, 1.1)
  const auto s2 = speedCells(*m, site2, SpeedMaskType::Absolute, 0.0, 0.02, 1.5);
  ASSERT_EQ(s2.size(), 1U);
  EXPECT_DOUBLE_EQ(s2[0].limit, 1.0);
}

}  // namespace
}  // namespace fleet::site
