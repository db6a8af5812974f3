#!/usr/bin/env bash
# deploy/prometheus/fleet-alerts.yml: `promtool check rules` accepts it, `promtool test rules`
# passes its unit tests (fleet-alerts.test.yml: each alert fires on its series, not before its
# `for:`, not on a healthy fleet), and every metric an alert reads is one a service exports (named
# in the code under services/ or sim/, or a process_* metric, or Prometheus' own `up`).
# Exit 77 (skip) only when promtool is missing.
set -euo pipefail
src=$1
dir=$src/deploy/prometheus
command -v promtool >/dev/null || { echo "promtool missing (Debian package prometheus): alert rules not checked"; exit 77; }
promtool check rules "$dir/fleet-alerts.yml"
(cd "$dir" && promtool test rules fleet-alerts.test.yml)
status=0
for m in $(grep -oE '\b(fleet|wms_adapter|robot_agent|traffic_manager|risk_map|vda5050_bridge)_[a-z_]+\b' "$dir/fleet-alerts.yml" |
           grep -v '^fleet_alerts' | sort -u); do
  if ! grep -rqF "\"$m\"" "$src/services" "$src/sim" --include='*.cpp' --include='*.hpp'; then
    echo "FAIL: fleet-alerts.yml reads $m, which no service exports"
    status=1
  fi
done
exit $status
