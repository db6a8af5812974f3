#pragma once

// The edge of a service process: every sample taken from DDS passes libs/validation before the
// service acts on it; refused ones are counted (for the service's stats) and logged, rate-limited.

#include <vector>

#include "fleet/service/runtime.hpp"
#include "fleet/validation/sample_checks.hpp"

namespace fleet::service {

template <class T>
bool admitSample(T& sample, validation::Rejections& counters, RateLimitedLog& log) {
  validation::Rejection why;
  if (validation::admit(sample, counters, &why)) {
    return true;
  }
  log.warn(why.topic + ":" + why.reason, "refused " + why.topic + ": " + why.detail);
  return false;
}

/// `samples` without those refused.
template <class T>
std::vector<T> admitted(std::vector<T> samples, validation::Rejections& counters, RateLimitedLog& log) {
  std::erase_if(samples, [&](T& s) { return !admitSample(s, counters, log); });
  return samples;
}

}  // namespace fleet::service
