#include "gz_lines.hpp"

namespace fleet::ctl {

bool readGzLine(gzFile f, std::string& line) {
  line.clear();
  char buf[1 << 16];
  while (gzgets(f, buf, sizeof buf) != nullptr) {
    line += buf;
    if (line.back() == '\n') {
      return true;
    }
  }
  return !line.empty();
}

}  // namespace fleet::ctl
