#pragma once

#include "fleet/avoidance/dynamic_window.hpp"
#include "fleet/avoidance/risk_stepping.hpp"
#include "fleet/avoidance/safety_layer.hpp"
#include "fleet/core/config.hpp"

namespace fleet::avoidance {

/// DWA parameters from a config object whose keys are DwaParams' field names (weights, samples,
/// horizon, ...). Missing keys keep `defaults`; wrong types, out-of-range values and unknown
/// keys are recorded as problems in `cfg` (the caller calls cfg.finish()).
DwaParams dwaParams(Config& cfg, const DwaParams& defaults = {});

/// Risk-stepping parameters from a config object whose keys are RiskSteppingParams' field names;
/// "rule" is "iso_level" (thesis §3.2.3, the default) or "weighted".
RiskSteppingParams riskSteppingParams(Config& cfg, const RiskSteppingParams& defaults = {});

/// Safety-layer zones from a config object whose keys are SafetyParams' field names.
SafetyParams safetyParams(Config& cfg);

}  // namespace fleet::avoidance
