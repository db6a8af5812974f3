// The registry and the text exposition format 0.0.4: HELP/TYPE lines, labels escaped, cumulative
// histogram buckets with +Inf, _sum and _count; names checked against Prometheus' conventions.

#include "fleet/metrics/registry.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "fleet/metrics/exposition.hpp"

using namespace fleet::metrics;

TEST(Registry, CountersAndGaugesInTheTextFormat) {
  Registry r;
  r.counter("x_requests_total", "Requests", {{"code", "200"}}).inc(3);
  r.counter("x_requests_total", "Requests", {{"code", "404"}}).inc();
  r.gauge("x_queue", "Queue length").set(2.5);
  EXPECT_EQ(r.exposition(),
            "# HELP x_queue Queue length\n"
            "# TYPE x_queue gauge\n"
            "x_queue 2.5\n"
            "# HELP x_requests_total Requests\n"
            "# TYPE x_requests_total counter\n"
            "x_requests_total{code=\"200\"} 3\n"
            "x_requests_total{code=\"404\"} 1\n");
}

TEST(Registry, TheSameNameAndLabelsGiveTheSameMetric) {
  Registry r;
  auto& a = r.counter("x_total", "X", {{"k", "v"}});
  auto& b = r.counter("x_total", "X", {{"k", "v"}});
  EXPECT_EQ(&a, &b);
  a.inc();
  EXPECT_EQ(b.value(), 1u);
}

TEST(Registry, HistogramBucketsAreCumulativeWithInfSumAndCount) {
  Registry r;
  auto& h = r.histogram("x_seconds", "Latency", {0.1, 1.0}, {{"op", "get"}});
  h.observe(0.05);
  h.observe(0.5);
  h.observe(3.0);
  EXPECT_EQ(r.exposition(),
            "# HELP x_seconds Latency\n"
            "# TYPE x_seconds histogram\n"
            "x_seconds_bucket{op=\"get\",le=\"0.1\"} 1\n"
            "x_seconds_bucket{op=\"get\",le=\"1\"} 2\n"
            "x_seconds_bucket{op=\"get\",le=\"+Inf\"} 3\n"
            "x_seconds_sum{op=\"get\"} 3.55\n"
            "x_seconds_count{op=\"get\"} 3\n");
}

TEST(Registry, LabelValuesAndHelpAreEscaped) {
  Registry r;
  r.gauge("x_g", "line one\nback\\slash", {{"v", "a\"b\\c\nd"}}).set(1);
  EXPECT_EQ(r.exposition(),
            "# HELP x_g line one\\nback\\\\slash\n"
            "# TYPE x_g gauge\n"
            "x_g{v=\"a\\\"b\\\\c\\nd\"} 1\n");
}

TEST(Registry, RefusesNamesAgainstTheConventions) {
  Registry r;
  EXPECT_THROW(r.counter("x_requests", "no _total"), std::invalid_argument);
  EXPECT_THROW(r.gauge("x_total", "a gauge named like a counter"), std::invalid_argument);
  EXPECT_THROW(r.gauge("9x", "bad start"), std::invalid_argument);
  EXPECT_THROW(r.gauge("x-y", "dash"), std::invalid_argument);
  EXPECT_THROW(r.gauge("x_g", "bad label", {{"__reserved", "v"}}), std::invalid_argument);
  EXPECT_THROW(r.histogram("x_h", "le is the bucket label", {1.0}, {{"le", "v"}}), std::invalid_argument);
  r.gauge("x_g", "help");
  EXPECT_THROW(r.counter("x_g", "help"), std::invalid_argument);
  EXPECT_THROW(r.gauge("x_g", "other help"), std::invalid_argument);
  EXPECT_THROW(r.gauge("x_g", "help", {{"k", "v"}}), std::invalid_argument);
  r.histogram("x_h", "h", {1.0});
  EXPECT_THROW(r.histogram("x_h", "h", {2.0}), std::invalid_argument);
}

TEST(Exposition, SpecialValuesAreSpelledAsPrometheusReadsThem) {
  EXPECT_EQ(formatValue(INFINITY), "+Inf");
  EXPECT_EQ(formatValue(-INFINITY), "-Inf");
  EXPECT_EQ(formatValue(std::nan("")), "NaN");
  EXPECT_EQ(formatValue(0.1), "0.1");
  EXPECT_EQ(formatValue(1e-5), "1e-05");
  EXPECT_TRUE(validMetricName("a:b_c9"));
  EXPECT_FALSE(validMetricName(""));
  EXPECT_TRUE(validLabelName("_x"));
  EXPECT_FALSE(validLabelName("a:b"));
}

TEST(Gauge, AddGoesUpAndDown) {
  Gauge g;
  g.add(2.0);
  g.add(-0.5);
  EXPECT_DOUBLE_EQ(g.value(), 1.5);
}
