#include "fleet/metrics/registry.hpp"

#include <stdexcept>

#include "fleet/metrics/exposition.hpp"

namespace fleet::metrics {
namespace {

std::vector<std::string> namesOf(const Labels& labels) {
  std::vector<std::string> n;
  for (const auto& [k, v] : labels) {
    n.push_back(k);
  }
  return n;
}

void labelText(std::string& out, const Labels& labels, const std::string& extraName = {},
               const std::string& extraValue = {}) {
  if (labels.empty() && extraName.empty()) {
    return;
  }
  out += '{';
  bool first = true;
  for (const auto& [k, v] : labels) {
    out += first ? "" : ",";
    out += k + "=\"" + escapeLabelValue(v) + "\"";
    first = false;
  }
  if (!extraName.empty()) {
    out += first ? "" : ",";
    out += extraName + "=\"" + extraValue + "\"";
  }
  out += '}';
}

const char* typeName(int kind) {
  static const char* names[] = {"counter", "gauge", "histogram"};
  return names[kind];
}

}  // namespace

Registry::Family& Registry::family(const std::string& name, Kind kind, const std::string& help,
                                   const Labels& labels) {
  if (!validMetricName(name)) {
    throw std::invalid_argument("metric name '" + name + "' is not [a-zA-Z_:][a-zA-Z0-9_:]*");
  }
  if (kind == Kind::counter && !name.ends_with("_total")) {
    throw std::invalid_argument("counter '" + name + "' must end in _total");
  }
  if (kind != Kind::counter && name.ends_with("_total")) {
    throw std::invalid_argument("'" + name + "' ends in _total but is not a counter");
  }
  for (const auto& [k, v] : labels) {
    if (!validLabelName(k) || (kind == Kind::histogram && k == "le")) {
      throw std::invalid_argument("metric '" + name + "': bad label name '" + k + "'");
    }
  }
  auto [it, fresh] = families_.try_emplace(name, Family{kind, help, namesOf(labels), {}, {}});
  Family& f = it->second;
  if (!fresh && (f.kind != kind || f.help != help || f.labelNames != namesOf(labels))) {
    throw std::invalid_argument("metric '" + name + "' registered again with another type, help or labels");
  }
  return f;
}

Counter& Registry::counter(const std::string& name, const std::string& help, const Labels& labels) {
  std::lock_guard lock(m_);
  auto& f = family(name, Kind::counter, help, labels);
  auto [it, fresh] = f.children.try_emplace(labels, Metric{});
  if (fresh) {
    it->second = std::make_unique<Counter>();
  }
  return *std::get<std::unique_ptr<Counter>>(it->second);
}

Gauge& Registry::gauge(const std::string& name, const std::string& help, const Labels& labels) {
  std::lock_guard lock(m_);
  auto& f = family(name, Kind::gauge, help, labels);
  auto [it, fresh] = f.children.try_emplace(labels, Metric{});
  if (fresh) {
    it->second = std::make_unique<Gauge>();
  }
  return *std::get<std::unique_ptr<Gauge>>(it->second);
}

Histogram& Registry::histogram(const std::string& name, const std::string& help,
                               const std::vector<double>& bounds, const Labels& labels) {
  std::lock_guard lock(m_);
  auto& f = family(name, Kind::histogram, help, labels);
  if (f.children.empty()) {
    f.bounds = bounds;
  } else if (f.bounds != bounds) {
    throw std::invalid_argument("histogram '" + name + "' registered again with other buckets");
  }
  auto [it, fresh] = f.children.try_emplace(labels, Metric{});
  if (fresh) {
    it->second = std::make_unique<Histogram>(bounds);
  }
  return *std::get<std::unique_ptr<Histogram>>(it->second);
}

std::string Registry::exposition() const {
  std::lock_guard lock(m_);
  std::string out;
  for (const auto& [name, f] : families_) {
    out += "# HELP " + name + " " + escapeHelp(f.help) + "\n";
    out += "# TYPE " + name + " " + typeName(static_cast<int>(f.kind)) + "\n";
    for (const auto& [labels, metric] : f.children) {
      if (const auto* c = std::get_if<std::unique_ptr<Counter>>(&metric)) {
        out += name;
        labelText(out, labels);
        out += " " + std::to_string((*c)->value()) + "\n";
      } else if (const auto* g = std::get_if<std::unique_ptr<Gauge>>(&metric)) {
        out += name;
        labelText(out, labels);
        out += " " + formatValue((*g)->value()) + "\n";
      } else {
        const auto s = std::get<std::unique_ptr<Histogram>>(metric)->snapshot();
        std::uint64_t cumulative = 0;
        for (std::size_t i = 0; i <= s.bounds.size(); ++i) {
          cumulative += s.counts[i];
          out += name + "_bucket";
          labelText(out, labels, "le", i < s.bounds.size() ? formatValue(s.bounds[i]) : "+Inf");
          out += " " + std::to_string(cumulative) + "\n";
        }
        out += name + "_sum";
        labelText(out, labels);
        out += " " + formatValue(s.sum) + "\n";
        out += name + "_count";
        labelText(out, labels);
        out += " " + std::to_string(s.count) + "\n";
      }
    }
  }
  return out;
}

}  // namespace fleet::metrics
