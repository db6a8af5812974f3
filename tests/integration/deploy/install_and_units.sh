#!/usr/bin/env bash
# `cmake --install` into a temporary prefix: the binaries run (--version), the docs, LICENSE and
# dashboard are there, and every systemd unit (paths filled in for that prefix) passes
# `systemd-analyze verify`. Exit 77 (skip) only when systemd-analyze is missing.
set -euo pipefail
src=$1 build=$2
root=$(mktemp -d)
trap 'rm -rf "$root"' EXIT
cmake --install "$build" --prefix "$root/usr" >/dev/null
for b in fleet_manager wms_adapter risk_map robot_agent traffic_manager fleet-sim fleetctl fleet-probe; do
  "$root/usr/bin/$b" --version | grep -q "$(sed -n 's/^project(fleet VERSION \([0-9.]*\).*/\1/p' "$src/CMakeLists.txt")" ||
    { echo "installed $b does not print the project version"; exit 1; }
done
for f in share/doc/fleet/LICENSE share/doc/fleet/operator-guide.md share/fleet/grafana-dashboard.json \
         share/fleet/cyclonedds-local.xml share/fleet/examples/small_warehouse.site.json; do
  [[ -s $root/usr/$f ]] || { echo "not installed: $f"; exit 1; }
done
grep -q "Apache License" "$root/usr/share/doc/fleet/LICENSE"
units=$root/usr/lib/systemd/system
n=$(ls "$units"/*.service | wc -l)
[[ $n -ge 5 ]] || { echo "only $n units installed"; exit 1; }
grep -q "ExecStart=$root/usr/bin/fleet_manager " "$units/fleet-manager.service" || { echo "unit paths not filled in"; exit 1; }
command -v systemd-analyze >/dev/null || { echo "systemd-analyze missing (Debian package systemd): units not verified"; exit 77; }
# A template is verified as one of its instances.
cp "$units/fleet-robot-agent@.service" "$units/fleet-robot-agent@r1.service"
fail=0
for u in "$units"/*.service; do
  [[ $u == *@.service ]] && continue
  if ! out=$(systemd-analyze verify --man=no "$u" 2>&1) || [[ -n $out ]]; then
    echo "$(basename "$u"): $out"
    fail=1
  fi
done
[[ $fail -eq 0 ]] && echo "install: $n units verified"
exit $fail
