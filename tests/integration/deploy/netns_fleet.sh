#!/usr/bin/env bash
# Multi-host test: three network namespaces ("hosts" of this test's own making) joined by veth
# pairs to a bridge in a fourth, on the private subnet 10.200.$NET.0/24. The fleet manager and the
# traffic manager run in host A, the simulator, robot agent and risk map in host B, the WMS adapter
# in host C; every process uses the LAN profile deploy/cyclonedds-lan.xml (unicast discovery to the
# three hosts' addresses, no multicast, pinned to the host's veth). A task posted to the WMS
# adapter's HTTP API in host C must reach `done`, the robot driving the traffic manager's releases
# across the hosts. Namespaces and processes are removed on every exit. Exit 77 (ctest skip) only
# when `ip netns add` is not permitted.
# With "secure", DDS Security is on: `scripts/dds-security deployment` makes the identities and each
# process adds its own security.xml to the LAN profile; a process in host C without a certificate
# then writes Tasks for 3 s, and none of them may reach the manager.
# Usage: netns_fleet.sh SOURCE_DIR BUILD_DIR [secure]
set -uo pipefail
SRC=$1
B=$2
SECURE=0
[[ ${3:-} == secure ]] && SECURE=1
# shellcheck source=uncertified_writer.sh
source "$(dirname "${BASH_SOURCE[0]}")/uncertified_writer.sh"
cd "$SRC"
t0=$SECONDS
fail() { echo "FAIL: $*"; exit 1; }
ID=$$
NET=$((ID % 200 + 20))  # one /24 per concurrent run
HUB=fleet-hub-$ID
hosts=(A B C)
pids=()
dir=$(mktemp -d /tmp/fleet-netns.XXXXXX)
cleanup() {
  for p in "${pids[@]}"; do kill -TERM "$p" 2>/dev/null; done
  sleep 0.3
  for p in "${pids[@]}"; do kill -KILL "$p" 2>/dev/null; done
  wait 2>/dev/null
  if [[ ${ok:-0} != 1 ]]; then
    for f in "$dir"/*.log; do echo "--- $f"; tail -n 20 "$f"; done
  fi
  for h in "${hosts[@]}"; do ip netns del "fleet-$h-$ID" 2>/dev/null; done
  ip netns del "$HUB" 2>/dev/null
  rm -rf "$dir"
}
trap cleanup EXIT

if ! out=$(ip netns add "$HUB" 2>&1); then
  echo "SKIP: network namespaces are not permitted here: $out"
  exit 77
fi
ip -n "$HUB" link add br0 type bridge || fail "no bridge in the hub namespace"
ip -n "$HUB" link set br0 up
i=0
declare -A addr
for h in "${hosts[@]}"; do
  i=$((i + 1))
  ns=fleet-$h-$ID
  addr[$h]=10.200.$NET.$i
  ip netns add "$ns" || fail "ip netns add $ns"
  ip link add "fh$h$ID" netns "$HUB" type veth peer name "veth$h" netns "$ns" || fail "veth for $h"
  ip -n "$HUB" link set "fh$h$ID" master br0 up
  ip -n "$ns" addr add "${addr[$h]}/24" dev "veth$h"
  ip -n "$ns" link set "veth$h" up
  ip -n "$ns" link set lo up
done

scenario=$SRC/sim/scenarios/one_robot.json
cat >"$dir/manager.json" <<JSON
{"stations": "$scenario", "db": "$dir/fleet.db", "clock": "sim", "lease_s": 3.0}
JSON
echo "{\"site\": \"$scenario\", \"grid\": {\"resolution\": 0.1}, \"clock\": \"sim\", \"lockstep\": true, \"rate_hz\": 2}" \
  >"$dir/risk_map.json"
echo "{\"site\": \"$scenario\", \"clock\": \"sim\", \"lockstep\": true}" >"$dir/traffic_manager.json"
printf 'id,kind,pickup,dropoff,load_s,unload_s\njob-1,transport,P-2,D-1,2,2\n' >"$dir/tasks.csv"

if ((SECURE)); then
  scripts/dds-security deployment "$dir/dds" >"$dir/dds-security.log" 2>&1 ||
    { cat "$dir/dds-security.log"; fail "scripts/dds-security deployment failed"; }
fi
declare -A identity=([fleet_manager]=fleet-manager [wms_adapter]=wms-adapter [risk_map]=risk-map
  [traffic_manager]=traffic-manager [robot_agent]=agents [fleet-sim]=simulator)
on() {  # on HOST NAME CMD...: a service in that host's namespace with the LAN profile
  local h=$1 name=$2 uri="file://$SRC/deploy/cyclonedds-lan.xml"
  shift 2
  ((SECURE)) && [[ -n ${identity[$name]:-} ]] && uri+=",file://$dir/dds/${identity[$name]}/security.xml"
  ip netns exec "fleet-$h-$ID" env FLEET_DDS_DOMAIN=0 CYCLONEDDS_URI="$uri" \
    FLEET_DDS_INTERFACE="veth$h" FLEET_DDS_PEER1="${addr[A]}" FLEET_DDS_PEER2="${addr[B]}" \
    FLEET_DDS_PEER3="${addr[C]}" "$@" >"$dir/$name.log" 2>&1 &
  pids+=($!)
}
on A fleet_manager "$B/services/fleet_manager/fleet_manager" --config "$dir/manager.json" --log-level info
on A traffic_manager "$B/services/traffic_manager/traffic_manager" --config "$dir/traffic_manager.json" \
  --id traffic_manager --log-level info
on C wms_adapter "$B/services/wms_adapter/wms_adapter" --stations "$scenario" --port 8080 --log-level info
on B risk_map "$B/services/risk_map/risk_map" --config "$dir/risk_map.json" --id risk_map --log-level info
on B robot_agent "$B/services/robot_agent/robot_agent" --scenario "$scenario" --clock lockstep --id agents \
  --log-level info
ctl() { ip netns exec "fleet-C-$ID" "$B/services/fleetctl/fleetctl" --url http://127.0.0.1:8080 "$@"; }
for _ in $(seq 60); do ctl health >/dev/null 2>&1 && break; sleep 0.5; done
ctl submit "$dir/tasks.csv" | tee "$dir/submit.txt"
grep -q 'submitted 1 tasks, 0 refused' "$dir/submit.txt" || fail "the WMS adapter did not accept the task"
# The manager runs on the wall clock and learns the robot only once the simulator steps, while
# lockstep runs ~250x real time: the assignment can land ~90 s into the simulation (it did once,
# and 150 s then left the robot 56 s for a ~75 s task). 600 s leaves room and takes ~2 s of wall time.
on B fleet-sim "$B/sim/src/fleet-sim" --scenario "$scenario" --clock lockstep --participants 3 --duration 600 \
  --summary "$dir/summary.json" --log-level info

state=""
for _ in $(seq 180); do
  state=$(ctl task job-1 2>/dev/null | python3 -c 'import json,sys; print(json.load(sys.stdin).get("state",""))' 2>/dev/null)
  [[ $state == done || $state == failed ]] && break
  sleep 1
done
echo "task job-1: $state after $((SECONDS - t0)) s (managers in host A, simulator and agent in B, WMS adapter in C)"
[[ $state == done ]] || fail "the task did not reach done across the namespaces (last state '$state')"
# A participant without a certificate in host C writes Tasks straight onto the domain, past the
# adapter. Without security they reach the manager (the check below can fail); with it, none may.
on C rogue "$B/tests/integration/security/dds_probe" write 3 rogue
wait "${pids[-1]}"
echo "uncertified writer: exit $? $(tail -n 1 "$dir/rogue.log")"
check_uncertified_writer writer
for p in "${pids[@]:0:5}"; do kill -0 "$p" 2>/dev/null || fail "a service exited early (pid $p)"; done
ok=1
echo "PASS: fleet across network namespaces$( ((SECURE)) && echo " with DDS Security") in $((SECONDS - t0)) s"
