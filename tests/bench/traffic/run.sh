#!/usr/bin/env bash
# traffic_bench (per-step planning time on warehouse-10-20-10-2-1), then, when PIBT2_DIR points at a
# checkout of Kei18/pibt2, the MAPD comparison on pibt2's own instance (map/warehouse.map and its
# .pd), both sides in the same run: pibt2's PIBT and TP (its `mapd` built here out of tree) and
# `fleetctl traffic-bench --mapd` on the same map, agents 10/30/50, task frequency 1 and 10, 500
# tasks, seeds 0..SEEDS-1 (default 10), mean over seeds.
#
# Getting pibt2 (its code is never committed here):
#   git clone --recursive https://github.com/Kei18/pibt2 /path/pibt2
#   (or git clone ... && git -C /path/pibt2 submodule update --init third_party/grid-pathfinding)
# Only pibt2/, mapd.cpp, map/ and third_party/grid-pathfinding/graph are used; pibt2's googletest
# and openFrameworks submodules are not needed. GCC 12 needs <cstring> in grid-pathfinding's
# graph.cpp: it is force-included here (-include cstring), the checkout is not modified.
#
# Usage: run.sh <traffic_bench exe> <json out> [benchmark args]
#        PIBT2_DIR=/path/pibt2 [SEEDS=10] run.sh ...
set -euo pipefail
exe=$1
out=$2
shift 2
echo "-- traffic_bench (PIBT step, lifelong, warehouse-10-20-10-2-1)"
"$exe" --benchmark_out="$out" --benchmark_out_format=json "$@"

if [[ -z "${PIBT2_DIR:-}" ]]; then
  echo "-- pibt2 MAPD comparison skipped: set PIBT2_DIR to a pibt2 checkout (see the top of $0)"
  exit 0
fi
build=$(cd "$(dirname "$exe")/../../.." && pwd)
fleetctl=$build/services/fleetctl/fleetctl
[[ -x "$fleetctl" ]] || { echo "run.sh: $fleetctl not built" >&2; exit 2; }
pibt2=$(cd "$PIBT2_DIR" && pwd)
graph=$pibt2/third_party/grid-pathfinding/graph
[[ -f "$pibt2/mapd.cpp" && -d "$graph/src" ]] || {
  echo "run.sh: $pibt2 lacks mapd.cpp or third_party/grid-pathfinding (clone with --recursive)" >&2
  exit 2
}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
echo "-- building pibt2's mapd out of tree ($work) with its own flags (-O3 -march=native)"
g++ -std=c++17 -O3 -march=native -mtune=native -include cstring -D_MAPDIR_="\"$pibt2/map/\"" \
  -I"$pibt2/pibt2/include" -I"$graph/include" "$pibt2"/pibt2/src/*.cpp "$graph"/src/*.cpp "$pibt2/mapd.cpp" \
  -o "$work/mapd"
echo "-- our fleetctl: $fleetctl ($(grep -m1 CMAKE_BUILD_TYPE: "$build/CMakeCache.txt" | cut -d= -f2))"

seeds=${SEEDS:-10}
results=$work/results.csv
echo "agents,frequency,seed,solver,solved,service_time,makespan,comp_time_ms,pre_ms" >"$results"
value() { sed -n "s/^$1=//p" | head -n 1; }
for agents in 10 30 50; do
  for freq in 1 10; do
    for ((seed = 0; seed < seeds; ++seed)); do
      cat >"$work/ins.txt" <<EOF
map_file=warehouse.map
agents=$agents
seed=$seed
task_frequency=$freq
task_num=500
max_timestep=3000
max_comp_time=30000
EOF
      for solver in PIBT TP; do
        # -d: the distance table pibt2's experiments use (Floyd-Warshall beforehand, not in comp_time;
        # ours likewise makes its pickup and delivery tables before the run, printed apart).
        (cd "$work" && ./mapd -i ins.txt -s "$solver" -o res.txt -d -L >/dev/null)
        r=$(cat "$work/res.txt")
        echo "$agents,$freq,$seed,pibt2-$solver,$(value solved <<<"$r"),$(value service_time <<<"$r"),$(value makespan <<<"$r"),$(value comp_time <<<"$r"),$(value preprocessing_comp_time <<<"$r")" >>"$results"
      done
      r=$("$fleetctl" traffic-bench --mapd --map "$pibt2/map/warehouse.map" --pd "$pibt2/map/warehouse.map.pd" \
        --agents "$agents" --tasks 500 --frequency "$freq" --seed "$seed" --max-steps 3000 || true)
      echo "$agents,$freq,$seed,ours-PIBT,$(value solved <<<"$r"),$(value service_time <<<"$r"),$(value makespan <<<"$r"),$(value comp_time_ms <<<"$r"),$(value preprocessing_ms <<<"$r")" >>"$results"
    done
  done
done
cp "$results" "${out%.json}-mapd.csv"
python3 - "$results" <<'PY'
import csv, statistics, sys
rows = list(csv.DictReader(open(sys.argv[1])))
groups = {}
for r in rows:
    groups.setdefault((int(r["agents"]), float(r["frequency"]), r["solver"]), []).append(r)
print(f"MAPD on pibt2's warehouse.map (500 tasks, {len(rows) // (len(groups) or 1)} seeds, mean over seeds; "
      "comp ms: the whole run, pre ms: distance tables made before it, apart as pibt2 reports them)")
print(f"{'agents':>6} {'freq':>4} {'solver':<10} {'solved':>6} {'service time':>12} {'makespan':>8} "
      f"{'comp ms':>8} {'ms/step':>8} {'pre ms':>7}")
for (agents, freq, solver), rs in sorted(groups.items()):
    ok = [r for r in rs if r["solved"] == "1"]
    mean = lambda k: statistics.mean(float(r[k]) for r in ok) if ok else float("nan")
    per_step = statistics.mean(float(r["comp_time_ms"]) / float(r["makespan"]) for r in ok) if ok else float("nan")
    print(f"{agents:>6} {freq:>4g} {solver:<10} {len(ok):>3}/{len(rs):<2} {mean('service_time'):>12.2f} "
          f"{mean('makespan'):>8.1f} {mean('comp_time_ms'):>8.1f} {per_step:>8.4f} {mean('pre_ms'):>7.1f}")
PY
