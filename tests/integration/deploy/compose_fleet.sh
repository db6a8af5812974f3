#!/usr/bin/env bash
# CI test of deploy/compose.yaml with podman-compose: builds the images from the host build, starts
# the services each in its own container on the project's bridge network (DDS by unicast to the
# service names, no multicast), posts transport tasks from the host to the WMS adapter's API
# published on 127.0.0.1, and asserts that they reach `done` (DDS between all the containers), that
# every service is healthy, that no container joined a multicast group, and that fleetctl in the
# network reaches the adapter by its service name. Everything the run created (containers, network,
# files) is removed, also on failure. Exit 77 (ctest skip) only when podman cannot run containers
# here at all.
# Plain: deploy/compose.yaml with the development overlay deploy/compose.dev.yaml (two robots, both
# the robot agent's; no DDS Security, http) and the PostgreSQL overlays deploy/compose.postgres.yaml
# and compose.dev.postgres.yaml: the task store and the adapters' event log in the postgres
# container, two fleet managers and two WMS adapters. Both tasks must be done through compose.yaml's
# traffic manager, which must have released routes, while the active manager is killed (-9) as the
# simulator starts: the other must be active within 10 s, the killed one stand by when started
# again, and the second adapter must show the same tasks and the same event ids. With "secure": the secure default as deployed,
# deploy/compose.yaml and deploy/compose.vda5050.yaml without the dev overlays, the files of
# `scripts/dds-security site` (written by scripts/containers files): DDS Security with an identity per
# service, the traffic manager and the bridge included, https on the API (fleetctl trusts the site
# CA), and a VDA 5050 vehicle (robot r2 of two, the simulator's) through the mosquitto container and
# the vda5050-bridge, which must have sent the vehicle orders that it drove and be ready (it hears
# the broker); a service whose identity file is missing must exit 2 naming it. In both modes a
# container on the network without a certificate then writes Tasks straight onto the domain: they
# must reach the manager without security (so the check can fail) and must not with it.
# Usage: compose_fleet.sh SOURCE_DIR BUILD_DIR [secure]
set -uo pipefail
SRC=$1
export BUILD_DIR=$2
SECURE=0
[[ ${3:-} == secure ]] && SECURE=1
# shellcheck source=uncertified_writer.sh
source "$(dirname "${BASH_SOURCE[0]}")/uncertified_writer.sh"
# shellcheck source=fleet_checks.sh
source "$(dirname "${BASH_SOURCE[0]}")/fleet_checks.sh"
cd "$SRC" || exit 1
t0=$SECONDS
fail() { echo "FAIL: $*"; exit 1; }

command -v podman-compose >/dev/null || fail "podman-compose is not installed (scripts/setup installs it)"
# shellcheck source=podman_images.sh
source "$(dirname "${BASH_SOURCE[0]}")/podman_images.sh"
echo "images built after $((SECONDS - t0)) s"

# Leftovers of a run that was killed (ctest's timeout kills without clean-up); runs still going
# elsewhere keep theirs.
for n in $(podman network ls --format '{{.Name}}' | grep -E '^fleet-compose-[0-9]+_fleet$'); do
  pid=${n#fleet-compose-}
  pid=${pid%_fleet}
  kill -0 "$pid" 2>/dev/null && continue
  podman ps -aq --filter "label=io.podman.compose.project=fleet-compose-$pid" | xargs -r podman rm -f -t 1 >/dev/null 2>&1
  podman network rm -f "$n" >/dev/null 2>&1
done

P=fleet-compose-$$
NET=${P}_fleet
SERVICES=(fleet-manager wms-adapter risk-map traffic-manager robot-agent fleet-sim)
dir=$(mktemp -d /tmp/fleet-compose.XXXXXX)
files=(-f deploy/compose.yaml)
if ((SECURE)); then
  SERVICES+=(mosquitto vda5050-bridge)
  files+=(-f deploy/compose.vda5050.yaml)
else
  SERVICES+=(postgres fleet-manager-2 wms-adapter-2)
  files+=(-f deploy/compose.dev.yaml -f deploy/compose.postgres.yaml -f deploy/compose.dev.postgres.yaml)
fi
scenario=sim/scenarios/two_robots.json ntasks=2
compose() { timeout 120 podman-compose -p "$P" "${files[@]}" "$@"; }
cleanup() {
  if [[ ${ok:-0} != 1 ]]; then
    for s in "${SERVICES[@]}"; do
      echo "--- log of ${P}_${s}_1"
      podman logs --tail 30 "${P}_${s}_1" 2>&1
    done
  fi
  compose down >/dev/null 2>&1
  # podman-compose 1.0.3 leaves the network (and a container whose start it lost) behind.
  podman ps -aq --filter "label=io.podman.compose.project=$P" | xargs -r podman rm -f -t 1 >/dev/null 2>&1
  podman network rm -f "$NET" >/dev/null 2>&1
  podman volume rm -f "${P}_fleet-pg" >/dev/null 2>&1
  rm -rf "$dir"
}
trap cleanup EXIT

# A loopback port for the API outside the ephemeral range and outside the blocks of the C++ tests
# (20000-28399, tests/support/test_process.hpp).
port=""
for k in $(seq 0 99); do
  p=$((28400 + ($$ + k * 37) % 3000))
  if python3 -c 'import socket,sys; s=socket.socket(); s.bind(("127.0.0.1", int(sys.argv[1])))' "$p" 2>/dev/null; then
    port=$p
    break
  fi
done
[[ -n $port ]] || fail "no free loopback port for the API"
port2=$((port + 3000))  # the second adapter (PostgreSQL overlay)

# The broker's port inside the network: not MQTT's 1883, as every test's broker.
export FLEET_MQTT_PORT=$((18830 + $$ % 1000))
# Secure: scripts/containers files makes config/dds with scripts/dds-security site (the images'
# user owns the files, the CA key stays root's); plain: DEV=1, no dds/ and no https.
DEV=$((1 - SECURE)) VDA5050=$SECURE scripts/containers files "$dir" "$scenario" 150 "$ntasks" >/dev/null ||
  fail "writing the mounted files failed"
export FLEET_CONFIG_DIR=$dir/config FLEET_DATA_DIR=$dir/data FLEET_WMS_PORT=$port FLEET_SIM_SECONDS=150
export FLEET_WMS_PORT_2=$port2 FLEET_PG_PASSWORD=pg-$$-$RANDOM
if ((SECURE)); then
  FLEET_AGENT_ROBOTS=$(cat "$dir/config/agent_robots")
  export FLEET_AGENT_ROBOTS
  [[ -s $dir/config/dds/fleet-manager/security.xml && -s $dir/config/dds/https/wms-adapter/cert.pem ]] ||
    fail "scripts/containers files made no DDS identities or https certificate in $dir/config/dds"
  # A service whose identity is missing refuses to start: exit 2, the file named.
  podman run --rm --network none --user 65532 -v "$dir/config:/etc/fleet:ro" -e FLEET_DDS_SECURITY=required \
    -e FLEET_DDS_SECURITY_DIR=/etc/fleet/dds \
    -e CYCLONEDDS_URI=file:///usr/share/fleet/cyclonedds-compose.xml,file:///etc/fleet/dds/nobody/security.xml \
    localhost/fleet-risk-map:latest --config /etc/fleet/risk_map.json >"$dir/missing.log" 2>&1
  rc=$?
  ((rc == 2)) && grep -q "/etc/fleet/dds/nobody/security.xml" "$dir/missing.log" ||
    { cat "$dir/missing.log"; fail "a service without its identity file did not exit 2 naming it (exit $rc)"; }
  echo "a service without its identity file exits 2: $(grep -o 'CYCLONEDDS_URI names [^,]*' "$dir/missing.log")"
fi
# fleetctl is left out: podman-compose 1.0.3 ignores `profiles: [cli]`.
compose up -d "${SERVICES[@]}" >"$dir/up.log" 2>&1 || { tail -n 30 "$dir/up.log"; fail "podman-compose up failed"; }
echo "podman-compose up after $((SECONDS - t0)) s"

[[ $(podman network inspect --format '{{.DNSEnabled}}' "$NET" 2>/dev/null) == true ]] ||
  fail "network $NET has no DNS: the service names do not resolve (podman's CNI backend needs golang-github-containernetworking-plugin-dnsname; scripts/setup installs it)"
declare -A ip
for s in "${SERVICES[@]}"; do
  c=${P}_${s}_1
  [[ $(podman inspect --format '{{.State.Status}}' "$c" 2>/dev/null) == running ]] || fail "$c did not start"
  ip[$s]=$(podman inspect --format "{{(index .NetworkSettings.Networks \"$NET\").IPAddress}}" "$c")
  [[ -n ${ip[$s]} ]] || fail "$c is not on $NET"
done
echo "containers: $(for s in "${SERVICES[@]}"; do printf '%s=%s ' "$s" "${ip[$s]}"; done)"
[[ $(podman port "${P}_wms-adapter_1") == "8080/tcp -> 127.0.0.1:$port" ]] ||
  fail "the API is not published on 127.0.0.1:$port only: $(podman port "${P}_wms-adapter_1")"
# The active one of two fleet managers (its /readyz 200; the other's 503), waiting up to `$1` s.
active_manager() {
  local m
  for _ in $(seq $(($1 * 2))); do
    for m in fleet-manager fleet-manager-2; do
      podman exec "${P}_${m}_1" /usr/local/bin/fleet-probe /readyz >/dev/null 2>&1 && { echo "$m"; return 0; }
    done
    sleep 0.5
  done
  return 1
}

if ((SECURE)); then
  ctl() { "$BUILD_DIR/services/fleetctl/fleetctl" --url "https://127.0.0.1:$port" --ca-cert "$dir/config/dds/ca.pem" "$@"; }
else
  ctl() { "$BUILD_DIR/services/fleetctl/fleetctl" --url "http://127.0.0.1:$port" "$@"; }
fi
for _ in $(seq 60); do ctl health >/dev/null 2>&1 && break; sleep 0.5; done
if ((SECURE)); then  # https only: plain http on the API's port gets no answer
  ctl health >/dev/null 2>&1 || fail "the API does not answer https with the site CA's certificate"
  "$BUILD_DIR/services/fleetctl/fleetctl" --url "http://127.0.0.1:$port" health >/dev/null 2>&1 &&
    fail "the API answered plain http"
  echo "the API answers https (site CA) and not plain http"
fi
ctl submit "$dir/config/tasks.csv" | tee "$dir/submit.txt"
grep -q "submitted $ntasks tasks, 0 refused" "$dir/submit.txt" || fail "the WMS adapter did not accept the tasks"
if ((!SECURE)); then
  # Two managers on PostgreSQL: kill -9 of the active one with the tasks acknowledged, before the
  # simulator starts (lockstep runs the whole scenario in seconds); the other takes over and assigns.
  first=$(active_manager 30) || fail "no fleet manager is active"
  other=fleet-manager-2
  [[ $first == fleet-manager-2 ]] && other=fleet-manager
  podman exec "${P}_${other}_1" /usr/local/bin/fleet-probe /readyz >/dev/null 2>&1 && fail "both managers are ready"
  podman kill -s KILL "${P}_${first}_1" >/dev/null
  killed=$SECONDS
  for _ in $(seq 20); do
    podman exec "${P}_${other}_1" /usr/local/bin/fleet-probe /readyz >/dev/null 2>&1 && break
    sleep 0.5
  done
  podman exec "${P}_${other}_1" /usr/local/bin/fleet-probe /readyz >/dev/null 2>&1 ||
    fail "$other did not take over within 10 s of the kill of $first"
  echo "killed the active manager $first: $other active after $((SECONDS - killed)) s"
  podman start "${P}_${first}_1" >/dev/null || fail "$first did not start again"
  # The new active manager assigns the tasks it rebuilt from the store before the simulator runs.
  for _ in $(seq 40); do
    ctl task job-000 2>/dev/null | grep -q '"state": "queued"' || break
    sleep 0.5
  done
fi
touch "$dir/data/start"  # the simulator starts now (deploy/compose.yaml)

wait_tasks_done "$ntasks" 120
check_traffic_manager_released "${P}_traffic-manager_1"
if ((!SECURE)); then
  # The second adapter: the same tasks done, the same event ids (one log in the database).
  ctl2() { "$BUILD_DIR/services/fleetctl/fleetctl" --url "http://127.0.0.1:$port2" "$@"; }
  for ((k = 0; k < ntasks; ++k)); do
    id=$(printf 'job-%03d' "$k")
    ctl2 task "$id" | grep -q '"state": "done"' || fail "the second adapter does not show $id done"
  done
  ids() { "$@" follow --since 0 --count 4 --seconds 10 | python3 -c 'import json,sys; print(" ".join(str(json.loads(l)["event_id"]) for l in sys.stdin if l.strip()))'; }
  e1=$(ids ctl) e2=$(ids ctl2)
  [[ -n $e1 && $e1 == "$e2" ]] || fail "the adapters number the events differently: '$e1' and '$e2'"
  echo "both adapters show the tasks done and the events as $e1"
  # The killed manager, started again, stands by.
  standby=$(active_manager 5)
  [[ $standby == "$other" ]] || fail "after the restart of $first the active manager is '$standby', not $other"
fi
((SECURE)) && check_vehicle_took_part "${P}_vda5050-bridge_1" "$dir/data"

for s in "${SERVICES[@]}"; do
  [[ $s == fleet-sim ]] && continue
  c=${P}_${s}_1
  [[ $(podman inspect --format '{{.State.Status}}' "$c") == running ]] || fail "$c is no longer running"
  # A probe is a podman exec: on a loaded machine one may time out, so up to three tries.
  h=1
  for _ in 1 2 3; do podman healthcheck run "$c" >/dev/null 2>&1 && { h=0; break; }; sleep 1; done
  ((h == 0)) || fail "$c is unhealthy"
  # Multicast off: no group joined but the all-hosts group every interface is in (224.0.0.1).
  groups=$(podman exec "$c" cat /proc/net/igmp | awk 'length($1) == 8 && $1 ~ /^[0-9A-F]+$/ && $1 != "010000E0" {print $1}')
  [[ -z $groups ]] || fail "$c joined multicast groups $groups"
  echo "$c running, healthy, no multicast group"
done
# The agent keeps its robots' poses in the data volume (--pose-file), for a restarted container.
poses=$(python3 -c 'import json,sys; print(len(json.load(open(sys.argv[1]))["robots"]))' "$dir/data/agent_poses.json" 2>&1) ||
  fail "the robot agent wrote no readable pose file in the data volume: $poses"
((poses > 0)) || fail "the robot agent's pose file names no robot"
echo "robot agent: pose file with $poses robots in the data volume"
sim=$(podman inspect --format '{{.State.Status}} {{.State.ExitCode}}' "${P}_fleet-sim_1")
[[ $sim == "running 0" || $sim == "exited 0" ]] || fail "the simulator ended badly ($sim)"

# A container on the network with no certificate writes Tasks onto the domain, past the adapter.
probe=$BUILD_DIR/tests/integration/security/dds_probe
[[ -x $probe ]] || fail "$probe is not built"
podman run --rm --network "$NET" --user 65532 -e FLEET_DDS_DOMAIN=0 -e RES_OPTIONS=no-tld-query \
  -e CYCLONEDDS_URI=file:///usr/share/fleet/cyclonedds-compose.xml -v "$probe:/usr/local/bin/dds_probe:ro" \
  --entrypoint /usr/local/bin/dds_probe localhost/fleet-fleet-manager:latest write 4 rogue >"$dir/rogue.log" 2>&1
echo "uncertified container: exit $? $(tail -n 1 "$dir/rogue.log")"
check_uncertified_writer container

# The compose file's fleetctl: a client in the network, reaching the adapter by service name.
compose run --rm --no-deps -T fleetctl task job-000 >"$dir/run.log" 2>&1
grep -q '"state": "done"' "$dir/run.log" || { tail -n 20 "$dir/run.log"; fail "fleetctl in the network did not reach wms-adapter:8080"; }
echo "fleetctl in the network: job-000 done"
ok=1
echo "PASS: compose fleet test through the traffic manager$( ((SECURE)) && echo ", a VDA 5050 vehicle, DDS Security and https on (the secure default)" || echo " (the dev overlay)") in $((SECONDS - t0)) s"
