#pragma once

#include <string>
#include <vector>

#include "fleet/risk/regions.hpp"

namespace fleet::risk_render {

/// Writes the regions of a level grid as filled SVG paths (holes via the even-odd rule), y up.
bool writeRegionsSvg(const std::string& path, const fleet::risk::GridSpec& spec, int levels,
                     const std::vector<fleet::risk::Region>& regions);

}  // namespace fleet::risk_render
