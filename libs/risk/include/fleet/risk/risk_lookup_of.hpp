#pragma once

// The RiskMap sample as a risk lookup (libs/risk) for the agents and the traffic manager: the wire
// form's fields mapped once.

#include <memory>

#include "fleet/core/expected.hpp"
#include "fleet/messages/messages.hpp"
#include "fleet/risk/risk_lookup.hpp"

namespace fleet::risk {

/// Errors those of risk::RiskLookup::decode (every field a remote writer could get wrong).
Expected<std::shared_ptr<const risk::RiskLookup>> riskLookupOf(const msg::RiskMap& m);

}  // namespace fleet::risk
