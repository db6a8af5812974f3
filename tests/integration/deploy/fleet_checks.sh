# Sourced by compose_fleet.sh and containers_smoke.sh, with ctl() (fleetctl against the run's
# adapter), fail() and t0 defined.

# wait_tasks_done N SECONDS: tasks job-000 .. job-(N-1) each reach `done` within SECONDS.
wait_tasks_done() {
  local n=$1 limit=$2 k id state deadline
  for ((k = 0; k < n; ++k)); do
    id=$(printf 'job-%03d' "$k") state=""
    deadline=$((SECONDS + limit))
    while ((SECONDS < deadline)); do
      state=$(ctl task "$id" 2>/dev/null | python3 -c 'import json,sys; print(json.load(sys.stdin).get("state",""))' 2>/dev/null)
      [[ $state == done || $state == failed ]] && break
      sleep 1
    done
    echo "task $id: $state after $((SECONDS - t0)) s"
    [[ $state == done ]] || fail "task $id did not reach done (last state '$state')"
  done
}

# check_vehicle_took_part BRIDGE_CONTAINER DATA_DIR: the VDA 5050 vehicle r2 did its part through the
# broker: the bridge is ready (it hears the broker), sent it orders, and the simulator's summary
# has r2 driving at least 5 m.
check_vehicle_took_part() {
  local bridge=$1 data=$2 ready=1 orders driven
  for _ in 1 2 3; do podman exec "$bridge" /usr/local/bin/fleet-probe /readyz >/dev/null 2>&1 && { ready=0; break; }; sleep 1; done
  ((ready == 0)) || fail "$bridge is not ready (it does not hear the broker)"
  orders=$(podman exec "$bridge" /usr/local/bin/fleet-probe /metrics | awk '$1 == "vda5050_bridge_orders_total" {print $2}')
  for _ in $(seq 30); do [[ -f $data/sim_summary.json ]] && break; sleep 1; done
  driven=$(python3 -c 'import json,sys; print(int(json.load(open(sys.argv[1]))["per_robot"]["r2"]["distance_m"]))' "$data/sim_summary.json" 2>/dev/null)
  ((${orders:-0} >= 1 && ${driven:-0} >= 5)) ||
    fail "the VDA 5050 vehicle r2 took no part: the bridge sent ${orders:-no} orders, r2 drove ${driven:-?} m"
  echo "the VDA 5050 vehicle r2 drove $driven m on $orders order(s) through the broker; the bridge is ready"
}

# check_traffic_manager_released CONTAINER: the traffic manager in CONTAINER sent releases (every
# robot drives only what it releases: without them no robot moves).
check_traffic_manager_released() {
  local c=$1 releases
  releases=$(podman exec "$c" /usr/local/bin/fleet-probe /metrics 2>/dev/null |
    awk '$1 == "traffic_manager_releases_total" {print int($2)}')
  ((${releases:-0} >= 1)) || fail "the traffic manager $c sent no releases (${releases:-no metric})"
  echo "the traffic manager sent $releases releases"
}
