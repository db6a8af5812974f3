// The replay viewer renders: fleet-sim writes a self-contained HTML page, headless Chromium
// screenshots it (no network), and the PNG must show the map walls, robots and humans in their colours.

#include <gtest/gtest.h>
#include <zlib.h>

#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "fleet/transport/dds.hpp"
#include "test_process.hpp"

namespace {

struct Image {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> rgb;  // 3 bytes per pixel
};

std::uint32_t be32(const std::string& s, std::size_t at) {
  return (static_cast<std::uint32_t>(static_cast<unsigned char>(s[at])) << 24) |
         (static_cast<std::uint32_t>(static_cast<unsigned char>(s[at + 1])) << 16) |
         (static_cast<std::uint32_t>(static_cast<unsigned char>(s[at + 2])) << 8) |
         static_cast<std::uint32_t>(static_cast<unsigned char>(s[at + 3]));
}

int paeth(int a, int b, int c) {
  const int p = a + b - c;
  const int pa = std::abs(p - a);
  const int pb = std::abs(p - b);
  const int pc = std::abs(p - c);
  return (pa <= pb && pa <= pc) ? a : (pb <= pc ? b : c);
}

// Minimal PNG reader: 8-bit RGB or RGBA, not interlaced (what Chromium writes).
bool decodePng(const std::string& data, Image& img) {
  if (data.size() < 8 || data.compare(0, 8, "\x89PNG\r\n\x1a\n") != 0) {
    return false;
  }
  std::string idat;
  int channels = 0;
  for (std::size_t at = 8; at + 8 <= data.size();) {
    const std::uint32_t len = be32(data, at);
    const std::string type = data.substr(at + 4, 4);
    if (type == "IHDR") {
      img.width = static_cast<int>(be32(data, at + 8));
      img.height = static_cast<int>(be32(data, at + 12));
      const int depth = static_cast<unsigned char>(data[at + 16]);
      const int colour = static_cast<unsigned char>(data[at + 17]);
      const int interlace = static_cast<unsigned char>(data[at + 20]);
      if (depth != 8 || (colour != 2 && colour != 6) || interlace != 0) {
        return false;
      }
      channels = colour == 2 ? 3 : 4;
    } else if (type == "IDAT") {
      idat += data.substr(at + 8, len);
    }
    at += 12 + len;
  }
  const std::size_t stride = static_cast<std::size_t>(img.width) * static_cast<std::size_t>(channels);
  std::vector<std::uint8_t> raw((stride + 1) * static_cast<std::size_t>(img.height));
  uLongf rawLen = raw.size();
  if (channels == 0 || uncompress(raw.data(), &rawLen, reinterpret_cast<const Bytef*>(idat.data()),
                                  static_cast<uLong>(idat.size())) != Z_OK) {
    return false;
  }
  std::vector<std::uint8_t> prev(stride, 0);
  std::vector<std::uint8_t> cur(stride);
  img.rgb.clear();
  for (int y = 0; y < img.height; ++y) {
    const std::uint8_t* line = &raw[static_cast<std::size_t>(y) * (stride + 1)];
    const int filter = line[0];
    for (std::size_t i = 0; i < stride; ++i) {
      const int a = i >= static_cast<std::size_t>(channels) ? cur[i - static_cast<std::size_t>(channels)] : 0;
      const int b = prev[i];
      const int c =
          i >= static_cast<std::size_t>(channels) ? prev[i - static_cast<std::size_t>(channels)] : 0;
      const int x = line[1 + i];
      int v = x;
      switch (filter) {
        case 1:
          v = x + a;
          break;
        case 2:
          v = x + b;
          break;
        case 3:
          v = x + (a + b) / 2;
          break;
        case 4:
          v = x + paeth(a, b, c);
          break;
        default:
          break;
      }
      cur[i] = static_cast<std::uint8_t>(v & 0xff);
    }
    for (int px = 0; px < img.width; ++px) {
      for (int k = 0; k < 3; ++k) {
        img.rgb.push_back(cur[static_cast<std::size_t>(px * channels + k)]);
      }
    }
    prev.swap(cur);
  }
  return true;
}

std::size_t countColour(const Image& img, int r, int g, int b, int tol = 12) {
  std::size_t n = 0;
  for (std::size_t i = 0; i + 2 < img.rgb.size(); i += 3) {
    n += (std::abs(img.rgb[i] - r) <= tol && std::abs(img.rgb[i + 1] - g) <= tol &&
          std::abs(img.rgb[i + 2] - b) <= tol)
             ? 1
             : 0;
  }
  return n;
}

std::string slurp(const std::string& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

}  // namespace

TEST(SimViewer, HeadlessChromiumRendersMapRobotsAndHumans) {
  const char* chromium = "/usr/bin/chromium";
  if (!std::filesystem::exists(chromium)) {
    GTEST_SKIP() << "chromium not installed";
  }
  const auto dir = std::filesystem::temp_directory_path() / ("sim_viewer_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string html = (dir / "viewer.html").string();
  const std::string png = (dir / "shot.png").string();
  {
    // A risk map as the risk service would publish it (transient-local: the simulator gets it on
    // discovery): level 2 of 3 over the lower half of the 30 m x 15 m aisle map, 0.5 m cells.
    const std::string dom = std::to_string(fleet::test::uniqueDomain());
    setenv("FLEET_DDS_DOMAIN", dom.c_str(), 1);
    fleet::transport::Participant p;
    fleet::transport::Writer<fleet::msg::RiskMap> risk(p);
    fleet::msg::RiskMap m;
    m.resolution = 0.5;
    m.width = 60;
    m.height = 30;
    m.levels = 3;
    m.runs = {{2, 60 * 15}, {0, 60 * 15}};
    risk.write(m);
    // The traffic layer as the traffic manager would publish it: a lane of 20 nodes along y = 4 m
    // (nodes 0-9 queue places, 10-19 closed) and a release to r1 of a base and a horizon.
    fleet::transport::Writer<fleet::msg::Roadmap> roadmap(p);
    fleet::transport::Writer<fleet::msg::TrafficRelease> release(p);
    fleet::msg::Roadmap rm;
    rm.epoch = 1;
    rm.revision = 1;
    for (int i = 0; i < 20; ++i) {
      rm.nodes.push_back({i, 2.0 + 1.2 * i, 4.0});
      rm.kinds.push_back(i < 10 ? 3 : 0);
      rm.open.push_back(i < 10);
      if (i > 0) {
        rm.edges.push_back({i - 1, i, 1.5f, true});
        rm.edges.push_back({i, i - 1, 1.5f, true});
      }
    }
    roadmap.write(rm);
    fleet::msg::TrafficRelease rel;
    rel.robot_id = "r1";
    rel.epoch = 1;
    rel.seq = 1;
    rel.base = {{0, 2.0, 4.0}, {1, 3.2, 4.0}};
    rel.horizon = {{2, 4.4, 4.0}};
    release.write(rel);
    fleet::test::ChildProcess sim(
        FLEET_BINARY_DIR "/sim/src/fleet-sim",
        {"--scenario", FLEET_SOURCE_DIR "/sim/scenarios/aisle_crossing.json", "--clock", "wall", "--duration",
         "3", "--replay", (dir / "r.jsonl.gz").string(), "--html", html, "--log-level", "warn"},
        {{"FLEET_DDS_DOMAIN", dom}});
    ASSERT_EQ(sim.wait(std::chrono::seconds(60)), 0);
  }
  EXPECT_NE(slurp(html).find("\"risk\":{"), std::string::npos) << "risk map not recorded in the replay";
  EXPECT_NE(slurp(html).find("\"roadmap\":{"), std::string::npos) << "roadmap not recorded in the replay";
  EXPECT_NE(slurp(html).find("\"releases\":{\"r1\":{\"b\":[0,1]"), std::string::npos)
      << "r1's release not recorded in the replay";
  const std::string profile = (dir / "profile").string();
  const std::string cmd = std::string("timeout 90 ") + chromium +
                          " --headless --no-sandbox --disable-gpu --disable-quic --no-first-run"
                          " --disable-background-networking --disable-component-update --disable-sync"
                          " --user-data-dir=" +
                          profile + " --screenshot=" + png + " --window-size=1200,800 'file://" + html +
                          "#frame=20' > " + (dir / "chromium.log").string() + " 2>&1";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << slurp((dir / "chromium.log").string());
  Image img;
  ASSERT_TRUE(decodePng(slurp(png), img));
  EXPECT_EQ(img.width, 1200);
  EXPECT_EQ(img.height, 800);
  const std::size_t walls = countColour(img, 0x3c, 0x3c, 0x3c, 2);
  const std::size_t robots = countColour(img, 0xe8, 0x50, 0x1e);
  const std::size_t humans = countColour(img, 0x2a, 0x6f, 0xdb);
  EXPECT_GT(walls, 100000U) << "map not drawn";
  EXPECT_GT(robots, 4 * 100U) << "4 robots not drawn";
  EXPECT_GT(humans, 3 * 50U) << "3 humans not drawn";
  // Level 2 of 3 shaded over white: alpha 0.367 of (150, 0, 190) -> about (216, 161, 231).
  EXPECT_GT(countColour(img, 216, 161, 231, 6), 20000U) << "risk iso-levels not drawn";
  // The traffic layer: 10 closed nodes (filled red squares), 10 queue places (purple rings).
  const std::size_t closed = countColour(img, 0xd0, 0x00, 0x00, 8);
  const std::size_t queue = countColour(img, 0xa0, 0x20, 0xf0, 40);
  EXPECT_GT(closed, 10 * 10U) << "closed roadmap nodes not drawn";
  EXPECT_GT(queue, 10 * 15U) << "queue places not drawn";
  std::filesystem::remove_all(dir);
}
