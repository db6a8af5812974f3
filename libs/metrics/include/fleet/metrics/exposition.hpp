#pragma once

// Pieces of the Prometheus text exposition format 0.0.4:
// https://prometheus.io/docs/instrumenting/exposition_formats/

#include <string>
#include <string_view>

namespace fleet::metrics {

/// Metric names: [a-zA-Z_:][a-zA-Z0-9_:]*.
[[nodiscard]] bool validMetricName(std::string_view name);
/// Label names: [a-zA-Z_][a-zA-Z0-9_]*, not starting with "__" (reserved).
[[nodiscard]] bool validLabelName(std::string_view name);
/// A sample value: shortest text that reads back the same double; +Inf, -Inf, NaN as Prometheus
/// spells them.
[[nodiscard]] std::string formatValue(double v);
/// Label values escape backslash, double quote and newline.
[[nodiscard]] std::string escapeLabelValue(std::string_view v);
/// HELP text escapes backslash and newline.
[[nodiscard]] std::string escapeHelp(std::string_view v);

}  // namespace fleet::metrics
