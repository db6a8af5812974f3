#pragma once

#include "fleet/avoidance/dynamic_window.hpp"
#include "fleet/avoidance/safety_layer.hpp"
#include "fleet/core/config.hpp"

namespace fleet::avoidance {

/// DWA parameters from a config object whose keys are DwaParams' field names (weights, samples,
/// horizon, ...). Missing keys keep `defaults`; wrong types, out-of-range values and unknown
/// keys are recorded as problems in `cfg` (the caller calls cfg.finish()).
DwaParams dwaParams(Config& cfg, const DwaParams& defaults = {});

/// Safety-layer zones from a config object whose keys are SafetyParams' field names.
SafetyParams safetyParams(Config& cfg);

}  // namespace fleet::avoidance
