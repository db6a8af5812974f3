// PGM and PNG decoding for ROS map images. PNG goes through libpng's classic API rather than the
// simplified png_image one: the simplified API converts 16-bit and gAMA-tagged images to sRGB, and
// map_server reads the stored sample values as they are.

#include <png.h>

#include <algorithm>
#include <cctype>
#include <csetjmp>
#include <cstdio>
#include <cstring>

#include "fleet/planning/map_limits.hpp"
#include "fleet/site/ros_map.hpp"

namespace fleet::site {

namespace {

// A map has at most planning::kMaxMapCells cells (2^26), so an image of more pixels is refused
// before its pixels are allocated.
constexpr auto kMaxPixels = static_cast<std::uint64_t>(planning::kMaxMapCells);

Unexpected<Error> imageError(const std::string& source, const std::string& what) {
  return unexpected("map_image", source + ": " + what);
}

// Samples of 0..maxval to 0..255, rounded (as an image library would show them).
std::uint8_t to8(unsigned v, unsigned maxval) {
  return static_cast<std::uint8_t>(maxval == 255 ? v : (v * 255U + maxval / 2U) / maxval);
}

Expected<Image> decodePgm(std::string_view b, const std::string& source) {
  const bool ascii = b[1] == '2';
  std::size_t pos = 2;
  auto skipSpaceAndComments = [&] {
    while (pos < b.size()) {
      if (b[pos] == '#') {
        while (pos < b.size() && b[pos] != '\n' && b[pos] != '\r') {
          ++pos;
        }
      } else if (std::isspace(static_cast<unsigned char>(b[pos])) != 0) {
        ++pos;
      } else {
        break;
      }
    }
  };
  // Up to 10 digits, so no overflow in 64 bits; false when there is no number here.
  auto number = [&](std::uint64_t& out) {
    skipSpaceAndComments();
    std::size_t digits = 0;
    out = 0;
    while (pos < b.size() && std::isdigit(static_cast<unsigned char>(b[pos])) != 0 && digits < 10) {
      out = out * 10 + static_cast<std::uint64_t>(b[pos++] - '0');
      ++digits;
    }
    return digits > 0 && (pos == b.size() || std::isdigit(static_cast<unsigned char>(b[pos])) == 0);
  };
  std::uint64_t w = 0, h = 0, maxval = 0;
  if (!number(w) || !number(h) || !number(maxval)) {
    return imageError(source, "bad PGM header: expected width, height and maxval as decimal numbers");
  }
  if (w == 0 || h == 0) {
    return imageError(source, "PGM image has zero width or height");
  }
  if (w * h > kMaxPixels) {
    return imageError(source, "PGM header claims " + std::to_string(w) + " x " + std::to_string(h) +
                                  " pixels (more than the limit of 67108864 = 2^26)");
  }
  if (maxval == 0 || maxval > 65535) {
    return imageError(source, "PGM maxval " + std::to_string(maxval) + " is outside 1..65535");
  }
  const auto mv = static_cast<unsigned>(maxval);
  const std::size_t n = static_cast<std::size_t>(w * h);
  const std::size_t bps = mv > 255 ? 2 : 1;
  // Size checks come before the allocation: a short file must not cost 100 MB.
  if (ascii) {
    if ((b.size() - pos) / 2 + 1 < n) {  // each sample takes a digit and a separator
      return imageError(source, "PGM data is shorter than the header says: " + std::to_string(n) +
                                    " samples cannot fit in " + std::to_string(b.size() - pos) + " bytes");
    }
  } else {
    // P5: exactly one whitespace byte separates maxval from the samples.
    if (pos >= b.size() || std::isspace(static_cast<unsigned char>(b[pos])) == 0) {
      return imageError(source, "PGM header is not followed by whitespace and pixel data");
    }
    ++pos;
    if (b.size() - pos < n * bps) {
      return imageError(source, "PGM data is shorter than the header says: expected " +
                                    std::to_string(n * bps) + " bytes, found " +
                                    std::to_string(b.size() - pos));
    }
  }
  Image img{static_cast<int>(w), static_cast<int>(h), 1, {}};
  img.pixels.resize(n);
  auto store = [&](std::size_t k, unsigned v) -> Expected<void> {
    if (v > mv) {
      return imageError(source, "PGM sample " + std::to_string(v) + " at pixel " + std::to_string(k) +
                                    " exceeds maxval " + std::to_string(mv));
    }
    img.pixels[k] = to8(v, mv);
    return {};
  };
  if (ascii) {
    for (std::size_t k = 0; k < n; ++k) {
      std::uint64_t v = 0;
      if (!number(v)) {
        return imageError(source, "PGM data ends or is not a number after " + std::to_string(k) + " of " +
                                      std::to_string(n) + " samples");
      }
      if (auto ok = store(k, static_cast<unsigned>(std::min<std::uint64_t>(v, 65536))); !ok) {
        return unexpected(ok.error());
      }
    }
    return img;
  }
  const auto* d = reinterpret_cast<const unsigned char*>(b.data()) + pos;
  for (std::size_t k = 0; k < n; ++k) {
    const unsigned v = bps == 2 ? (unsigned{d[2 * k]} << 8U) | d[2 * k + 1] : d[k];
    if (auto ok = store(k, v); !ok) {
      return unexpected(ok.error());
    }
  }
  return img;
}

struct PngSource {
  const unsigned char* data = nullptr;
  std::size_t size = 0;
  std::size_t pos = 0;
  char error[160] = "";
};

void pngRead(png_structp png, png_bytep out, std::size_t n) {
  auto* src = static_cast<PngSource*>(png_get_io_ptr(png));
  if (n > src->size - src->pos) {
    png_error(png, "file is truncated");
  }
  std::memcpy(out, src->data + src->pos, n);
  src->pos += n;
}

[[noreturn]] void pngFail(png_structp png, png_const_charp msg) {
  auto* src = static_cast<PngSource*>(png_get_error_ptr(png));
  std::snprintf(src->error, sizeof src->error, "%s", msg);
  png_longjmp(png, 1);
}

void pngWarn(png_structp /*png*/, png_const_charp /*msg*/) {}  // libs do not log

struct PngLayout {
  std::uint32_t width = 0;
  std::uint32_t height = 0;
  int channels = 0;
  std::size_t rowBytes = 0;
  std::size_t storedRowBytes = 0;  ///< before expansion: what the compressed stream holds
  int passes = 1;
};

// libpng reports errors by longjmp to the setjmp below, so these two functions hold no object with
// a destructor; the structs are freed by the caller's PngReader.
bool pngReadLayout(png_structp png, png_infop info, PngLayout* out) {
  if (setjmp(png_jmpbuf(png)) != 0) {
    return false;
  }
  png_read_info(png, info);
  out->storedRowBytes = png_get_rowbytes(png, info);
  png_set_expand(png);    // palette -> RGB, grey below 8 bits -> 8 bits, tRNS -> alpha channel
  png_set_scale_16(png);  // 16 -> 8 bits, rounded
  out->passes = png_set_interlace_handling(png);
  png_read_update_info(png, info);
  out->width = png_get_image_width(png, info);
  out->height = png_get_image_height(png, info);
  out->channels = png_get_channels(png, info);
  out->rowBytes = png_get_rowbytes(png, info);
  return true;
}

bool pngReadRows(png_structp png, png_infop info, const PngLayout* layout, unsigned char* pixels) {
  if (setjmp(png_jmpbuf(png)) != 0) {
    return false;
  }
  for (int pass = 0; pass < layout->passes; ++pass) {
    for (std::uint32_t y = 0; y < layout->height; ++y) {
      png_read_row(png, pixels + static_cast<std::size_t>(y) * layout->rowBytes, nullptr);
    }
  }
  png_read_end(png, info);  // checks the rest of the file (CRCs, IEND): a cut file is an error
  return true;
}

struct PngReader {
  png_structp png = nullptr;
  png_infop info = nullptr;
  PngReader(const PngReader&) = delete;
  PngReader& operator=(const PngReader&) = delete;
  explicit PngReader(PngSource* src) {
    png = png_create_read_struct(PNG_LIBPNG_VER_STRING, src, pngFail, pngWarn);
    if (png != nullptr) {
      info = png_create_info_struct(png);
      png_set_read_fn(png, src, pngRead);
    }
  }
  ~PngReader() {
    if (png != nullptr) {
      png_destroy_read_struct(&png, info != nullptr ? &info : nullptr, nullptr);
    }
  }
};

Expected<Image> decodePng(std::string_view b, const std::string& source) {
  PngSource src;
  src.data = reinterpret_cast<const unsigned char*>(b.data());
  src.size = b.size();
  PngReader r(&src);
  if (r.png == nullptr || r.info == nullptr) {
    return imageError(source, "cannot initialise libpng");
  }
  PngLayout layout;
  if (!pngReadLayout(r.png, r.info, &layout)) {
    return imageError(source, std::string("corrupt PNG: ") + src.error);
  }
  const std::uint64_t n = std::uint64_t{layout.width} * layout.height;
  if (n == 0 || n > kMaxPixels) {
    return imageError(source, "PNG header claims " + std::to_string(layout.width) + " x " +
                                  std::to_string(layout.height) + " pixels (expected 1 to 67108864 = 2^26)");
  }
  // Deflate expands at most ~1032:1; a header promising more than that is lying, and we would rather
  // not allocate gigabytes to find out.
  const std::uint64_t stored = std::uint64_t{layout.height} * (layout.storedRowBytes + 1);
  if (stored / 1100 > b.size()) {
    return imageError(source, "PNG data is shorter than the header says: " + std::to_string(layout.width) +
                                  " x " + std::to_string(layout.height) + " pixels cannot fit in " +
                                  std::to_string(b.size()) + " bytes");
  }
  if (layout.channels < 1 || layout.channels > 4 ||
      layout.rowBytes != std::size_t{layout.width} * static_cast<std::size_t>(layout.channels)) {
    return imageError(source, "unsupported PNG pixel layout");
  }
  Image img{static_cast<int>(layout.width), static_cast<int>(layout.height), layout.channels, {}};
  img.pixels.resize(static_cast<std::size_t>(n) * static_cast<std::size_t>(layout.channels));
  if (!pngReadRows(r.png, r.info, &layout, img.pixels.data())) {
    return imageError(source, std::string("corrupt PNG: ") + src.error);
  }
  return img;
}

}  // namespace

Expected<Image> decodeImage(std::string_view bytes, const std::string& source) {
  static constexpr std::string_view kPngMagic{"\x89PNG\r\n\x1a\n", 8};
  if (bytes.substr(0, kPngMagic.size()) == kPngMagic) {
    return decodePng(bytes, source);
  }
  if (bytes.size() >= 3 && bytes[0] == 'P' && (bytes[1] == '2' || bytes[1] == '5') &&
      std::isspace(static_cast<unsigned char>(bytes[2])) != 0) {
    return decodePgm(bytes, source);
  }
  if (bytes.empty()) {
    return imageError(source, "file is empty");
  }
  return imageError(source, "not a PGM (P2/P5) or PNG image (unrecognised magic bytes)");
}

}  // namespace fleet::site
