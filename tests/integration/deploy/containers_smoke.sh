#!/usr/bin/env bash
# CI smoke test of the service containers: builds the images from the host build, starts the
# small-fleet pod (simulator, risk map, fleet manager, WMS adapter, traffic manager, robot agent)
# with `podman play kube --network none` in its secure default (DDS Security with an identity per
# service, https on the API; scripts/containers makes the files), plus deploy/fleet-pod.vda5050.yaml's MQTT broker and VDA
# 5050 bridge (VDA5050=1: of two robots, r2 is the simulator's VDA 5050 vehicle), posts two
# transport tasks over HTTP from inside the pod and asserts that every container started and stays
# healthy (liveness), ready, with metrics, not as root, that both tasks reached `done` (DDS between
# all the services, MQTT between the bridge and the vehicle) through the traffic manager's
# releases, and that the vehicle drove on the bridge's orders. (The plain pod's services without the
# overlay: compose_fleet runs them from compose.yaml, which compose_matches_pod holds equal to the
# pod; kube_play the Kubernetes manifests.) Exit 77 (ctest skip) only when podman cannot run
# containers on this machine at all. Usage: containers_smoke.sh SOURCE_DIR BUILD_DIR
set -uo pipefail
SRC=$1
export BUILD_DIR=$2
cd "$SRC"
t0=$SECONDS
fail() { echo "FAIL: $*"; exit 1; }

# shellcheck source=fleet_checks.sh
source "$(dirname "${BASH_SOURCE[0]}")/fleet_checks.sh"
# shellcheck source=podman_images.sh
source "$(dirname "${BASH_SOURCE[0]}")/podman_images.sh"
echo "images built after $((SECONDS - t0)) s"

export POD=fleet-smoke-$$
dir=$(mktemp -d /tmp/fleet-smoke.XXXXXX)
cleanup() {
  if [[ ${ok:-0} != 1 ]]; then
    for c in fleet-manager wms-adapter risk-map robot-agent fleet-sim traffic-manager mosquitto vda5050-bridge; do
      echo "--- log of $POD-$c"
      podman logs --tail 30 "$POD-$c" 2>&1
    done
  fi
  podman pod rm -f -t 1 "$POD" >/dev/null 2>&1
  rm -rf "$dir"
}
trap cleanup EXIT
export FLEET_MQTT_PORT=$((18830 + $$ % 1000))  # not MQTT's 1883, as every test's broker
VDA5050=1 scripts/containers up "$dir" sim/scenarios/two_robots.json 150 2 || fail "podman play kube failed"

# The secure default (DDS Security, https): the API trusted through the site CA of config/dds.
ctl() { podman run --rm --pod "$POD" -v "$dir/config:/etc/fleet:ro" localhost/fleet-fleetctl \
  --url https://127.0.0.1:8080 --ca-cert /etc/fleet/dds/ca.pem "$@"; }
services=(fleet-manager wms-adapter risk-map robot-agent fleet-sim traffic-manager mosquitto vda5050-bridge)
for c in "${services[@]}"; do
  [[ $(podman inspect --format '{{.State.Status}}' "$POD-$c") == running ]] || fail "$POD-$c did not start"
done
for _ in $(seq 60); do ctl health >/dev/null 2>&1 && break; sleep 0.5; done
ctl submit /etc/fleet/tasks.csv | tee "$dir/submit.txt"
grep -q 'submitted 2 tasks, 0 refused' "$dir/submit.txt" || fail "the WMS adapter did not accept the tasks"
touch "$dir/data/start"  # the simulator starts now (deploy/fleet-pod.yaml)

wait_tasks_done 2 150
check_traffic_manager_released "$POD-traffic-manager"
check_vehicle_took_part "$POD-vda5050-bridge" "$dir/data"

h=1
for _ in 1 2 3; do podman healthcheck run "$POD-mosquitto" >/dev/null && { h=0; break; }; sleep 1; done
((h == 0)) || fail "$POD-mosquitto is unhealthy"
[[ $(podman exec "$POD-mosquitto" id -u) == 65532 ]] || fail "$POD-mosquitto runs as root"
for c in fleet-manager wms-adapter risk-map robot-agent traffic-manager vda5050-bridge; do
  [[ $(podman inspect --format '{{.State.Status}}' "$POD-$c") == running ]] || fail "$POD-$c is no longer running"
  # A probe is a podman exec: on a loaded machine one may time out, so up to three tries.
  h=1
  for _ in 1 2 3; do podman healthcheck run "$POD-$c" >/dev/null && { h=0; break; }; sleep 1; done
  ((h == 0)) || fail "$POD-$c is unhealthy"
  # Ready (the Pod's readinessProbe), serving metrics, and not root.
  # The agent is ready while a sensor source is matched: once the simulator has ended it must say so.
  if [[ $c == robot-agent && $(podman inspect --format '{{.State.Status}}' "$POD-fleet-sim") == exited ]]; then
    [[ $(podman exec "$POD-$c" /usr/local/bin/fleet-probe /readyz 2>&1) == "not ready: sensors" ]] ||
      fail "$POD-$c does not report its lost sensors"
  else
    podman exec "$POD-$c" /usr/local/bin/fleet-probe /readyz >/dev/null || fail "$POD-$c is not ready"
  fi
  podman exec "$POD-$c" /usr/local/bin/fleet-probe /metrics | grep '^fleet_build_info' >/dev/null ||
    fail "$POD-$c serves no metrics"
  [[ $(podman exec "$POD-$c" id -u) == 65532 ]] || fail "$POD-$c runs as $(podman exec "$POD-$c" id -u), not 65532"
  echo "$POD-$c running, healthy, ready, not root"
done
sim=$(podman inspect --format '{{.State.Status}} {{.State.ExitCode}}' "$POD-fleet-sim")
[[ $sim == "running 0" || $sim == "exited 0" ]] || fail "the simulator ended badly ($sim)"
ok=1
echo "PASS: containers smoke test in $((SECONDS - t0)) s"
