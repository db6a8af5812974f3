#include <string>
#include <vector>

#include "fleet/sim/replay.hpp"

namespace fleet::sim {

extern const char* const kViewerHtml;

std::string viewerHtml(const std::vector<std::string>& replayLines) {
  std::string data;
  for (const auto& l : replayLines) {
    // '<' only occurs inside JSON strings; \u003c keeps "</script>" out of the page.
    for (char c : l) {
      if (c == '<') {
        data += "\\u003c";
      } else {
        data += c;
      }
    }
    data += '\n';
  }
  std::string page = kViewerHtml;
  const std::string marker = "/*REPLAY-DATA*/";
  const auto at = page.find(marker);
  if (at != std::string::npos) {
    page.replace(at, marker.size(), data);
  }
  return page;
}

}  // namespace fleet::sim
