#pragma once

// The dashboard page's files (services/wms_adapter/web/), built into the adapter by
// embed_web.cmake so the page is served with nothing to install and no path to configure.

#include <string_view>

namespace fleet::wms {

struct WebFile {
  std::string_view body;
  std::string_view type;  // Content-Type
};

/// The file `name` ("index.html", "map_view.js"), or nullptr.
const WebFile* webFile(std::string_view name);

}  // namespace fleet::wms
