#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace fleet::risk_render {

/// 8-bit RGB image, row 0 at the top.
struct Image {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> rgb;  // width·height·3
};

/// Writes a PNG (colour type 2, zlib-compressed); false on I/O error.
bool writePng(const std::string& path, const Image& image);

}  // namespace fleet::risk_render
