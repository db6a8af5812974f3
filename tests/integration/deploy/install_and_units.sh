#!/usr/bin/env bash
# `cmake --install` into a temporary prefix. The programs are what the install put into bin/ (the
# build's install(TARGETS ...), no list here): each runs (--version prints the project version),
# and every program the build made under services/ and sim/ is among them. Every installed program
# but the tools has a systemd unit that runs it, hardened as the others; the docs, LICENSE and
# dashboard are there; every unit (paths filled in for that prefix) passes `systemd-analyze
# verify`; the robot agent's and the VDA 5050 bridge's units start after the traffic manager's and
# want it (their robots drive only what it releases). Every service unit is Type=notify with a
# watchdog (the services send READY=1, WATCHDOG=1, STOPPING=1: systemd_notify.hpp). Exit 77
# (skip) only when systemd-analyze is missing.
set -euo pipefail
src=$1 build=$2
root=$(mktemp -d)
trap 'rm -rf "$root"' EXIT
fail() { echo "FAIL: $*"; exit 1; }
version=$(sed -n 's/^project(fleet VERSION \([0-9.]*\).*/\1/p' "$src/CMakeLists.txt")
out=$(cmake --install "$build" --prefix "$root/usr")
mapfile -t programs < <(sed -n "s#^-- Installing: $root/usr/bin/##p" <<<"$out" | sort)
((${#programs[@]} > 0)) || fail "cmake --install put nothing into bin/"
for b in "${programs[@]}"; do
  "$root/usr/bin/$b" --version | grep -q "$version" || fail "installed $b does not print the project version $version"
done
echo "install: ${#programs[@]} programs, each prints $version: ${programs[*]}"
# A program of services/ or sim/ that the build makes but does not install is one forgotten in
# install(TARGETS ...) (CMakeLists.txt).
while IFS= read -r -d '' f; do
  cmp -s -n 4 "$f" <(printf '\177ELF') || continue
  [[ " ${programs[*]} " == *" $(basename "$f") "* ]] || fail "$f is built but not installed (install(TARGETS ...))"
done < <(find "$build/services" "$build/sim/src" -mindepth 1 -maxdepth 2 -path '*/CMakeFiles' -prune -o \
  -type f -perm -u+x -print0)
for f in share/doc/fleet/LICENSE share/doc/fleet/operator-guide.md share/fleet/grafana-dashboard.json share/fleet/fleet-alerts.yml \
         share/fleet/cyclonedds-local.xml share/fleet/examples/small_warehouse.site.json; do
  [[ -s $root/usr/$f ]] || fail "not installed: $f"
done
grep -q "Apache License" "$root/usr/share/doc/fleet/LICENSE"
units=$root/usr/lib/systemd/system
n=$(ls "$units"/*.service | wc -l)
grep -q "ExecStart=$root/usr/bin/fleet_manager " "$units/fleet-manager.service" || fail "unit paths not filled in"
# Every service has its unit; the tools (a CLI, the probe, the simulator, the risk renderer) have none.
for b in "${programs[@]}"; do
  case $b in fleetctl | fleet-probe | fleet-sim | risk_render) continue ;; esac
  u=$(grep -l "^ExecStart=$root/usr/bin/$b " "$units"/*.service) || fail "no unit runs $b"
  for line in DynamicUser=yes NoNewPrivileges=yes CapabilityBoundingSet= ProtectSystem=strict ProtectHome=yes \
              PrivateTmp=yes PrivateDevices=yes RestrictAddressFamilies= MemoryDenyWriteExecute=yes \
              SystemCallFilter=@system-service RestartPreventExitStatus=2 WantedBy=multi-user.target \
              Type=notify NotifyAccess=main WatchdogSec=; do
    grep -q "^$line" "$u" || fail "$(basename "$u") lacks $line"
  done
done
# Secure by default: every unit requires DDS Security with its identity of /etc/fleet/dds, its key a
# credential; the adapter requires https. The development drop-in turns both off.
for u in "$units"/*.service; do
  for line in "Environment=FLEET_DDS_SECURITY=required" "Environment=CYCLONEDDS_URI=.*,file:///etc/fleet/dds/[a-z0-9-]*/security.xml\$" \
              "LoadCredential=dds-key.pem:/etc/fleet/dds/" "SetCredential=dds-key.pem:not loaded: /etc/fleet/dds/"; do
    grep -q "^$line" "$u" || fail "$(basename "$u") lacks $line (DDS Security by default)"
  done
done
grep -q "^Environment=FLEET_WMS_TLS=required" "$units/fleet-wms-adapter.service" || fail "fleet-wms-adapter.service: https not required"
dev=$root/usr/share/fleet/systemd/dev-insecure.conf
[[ -s $dev ]] || fail "not installed: share/fleet/systemd/dev-insecure.conf"
grep -q "^Environment=FLEET_DDS_SECURITY=off FLEET_WMS_TLS=off" "$dev" || fail "dev-insecure.conf does not turn security off"
grep -q "^Environment=CYCLONEDDS_URI=file://$root/usr/share/fleet/cyclonedds-lan.xml$" "$dev" || fail "dev-insecure.conf: paths not filled in"
echo "install: every unit requires DDS Security (the adapter https); dev-insecure.conf turns them off"
for u in fleet-robot-agent@.service fleet-vda5050-bridge.service; do
  for dep in After Wants; do
    grep -q "^$dep=.*fleet-traffic-manager.service" "$units/$u" || fail "$u: no $dep=fleet-traffic-manager.service"
  done
done
command -v systemd-analyze >/dev/null || { echo "systemd-analyze missing (Debian package systemd): units not verified"; exit 77; }
# A template is verified as one of its instances; the units' dependencies on each other are found
# in the install's unit folder.
cp "$units/fleet-robot-agent@.service" "$units/fleet-robot-agent@r1.service"
status=0
for u in "$units"/*.service; do
  [[ $u == *@.service ]] && continue
  if ! out=$(SYSTEMD_UNIT_PATH="$units:" systemd-analyze verify --man=no "$u" 2>&1) || [[ -n $out ]]; then
    echo "$(basename "$u"): $out"
    status=1
  fi
done
# The same units with the development drop-in.
for u in fleet-manager.service fleet-wms-adapter.service; do
  mkdir -p "$units/$u.d"
  cp "$dev" "$units/$u.d/"
  if ! out=$(SYSTEMD_UNIT_PATH="$units:" systemd-analyze verify --man=no "$units/$u" 2>&1) || [[ -n $out ]]; then
    echo "$u with dev-insecure.conf: $out"
    status=1
  fi
done
[[ $status -eq 0 ]] && echo "install: $n units verified"
exit $status
