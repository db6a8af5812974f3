#pragma once

// The metrics of one process, by family (name, help, type) and label values. Registration and
// lookup take a lock; the returned Counter/Gauge/Histogram references stay valid for the registry's
// lifetime, so hot paths look a metric up once and then update it lock-free.

#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include "fleet/metrics/counter.hpp"
#include "fleet/metrics/histogram.hpp"

namespace fleet::metrics {

using Labels = std::vector<std::pair<std::string, std::string>>;

class Registry {
 public:
  /// `name` must end in `_total` (Prometheus convention for counters). Throws std::invalid_argument
  /// for a bad name or label, or a name registered before with another type, help or label names.
  Counter& counter(const std::string& name, const std::string& help, const Labels& labels = {});
  Gauge& gauge(const std::string& name, const std::string& help, const Labels& labels = {});
  /// The bounds of the first registration of `name` are the family's; later ones must match.
  Histogram& histogram(const std::string& name, const std::string& help, const std::vector<double>& bounds,
                       const Labels& labels = {});

  /// Every family in the text exposition format 0.0.4 (HELP and TYPE lines, sorted by name).
  [[nodiscard]] std::string exposition() const;

 private:
  enum class Kind { counter, gauge, histogram };
  using Metric = std::variant<std::unique_ptr<Counter>, std::unique_ptr<Gauge>, std::unique_ptr<Histogram>>;
  struct Family {
    Kind kind;
    std::string help;
    std::vector<std::string> labelNames;
    std::vector<double> bounds;
    std::map<Labels, Metric> children;
  };
  Family& family(const std::string& name, Kind kind, const std::string& help, const Labels& labels);

  mutable std::mutex m_;
  std::map<std::string, Family> families_;
};

}  // namespace fleet::metrics
