#!/usr/bin/env bash
# `fleetctl traffic-bench` end to end: a plan it writes passes the independent python checker, and
# bad input is refused with exit code 2 and a message naming what is wrong.
# Usage: traffic_bench_cli_test.sh FLEETCTL SOURCE_DIR WORK_DIR
set -uo pipefail
fleetctl=$1 src=$2 work=$3
rm -rf "$work" && mkdir -p "$work"
fail() { echo "FAIL: $*"; exit 1; }

python3 "$src/scripts/traffic-maps" "$work" >/dev/null || fail "traffic-maps"
map=$work/warehouse-10-20-10-2-1.map
for rot in avoid allow; do
  out=$("$fleetctl" traffic-bench --map "$map" --agents 300 --steps 150 --seed 3 --rotations "$rot" \
    --out "$work/plan-$rot.json") || fail "traffic-bench ($rot) exited with $?"
  grep -q '^throughput=' <<<"$out" || fail "no throughput line: $out"
  check=(python3 "$src/scripts/check-plan.py" "$map" "$work/plan-$rot.json")
  [[ $rot == avoid ]] && check+=(--rotations)
  "${check[@]}" || fail "check-plan.py refused the $rot plan"
done
# The checker is not a rubber stamp: a plan with two agents on one cell is refused.
python3 - "$work/plan-avoid.json" "$work/broken.json" <<'PY'
import json, sys
d = json.load(open(sys.argv[1]))
d["plan"][5][1] = d["plan"][5][0]
json.dump(d, open(sys.argv[2], "w"))
PY
python3 "$src/scripts/check-plan.py" "$map" "$work/broken.json" >/dev/null && fail "broken plan accepted"

# MAPD on a small generated instance: every task done, pibt2's figures printed.
printf '........\n.s.ss.s.\n........\n.e.e.e.e\n' >"$work/tiny.map.pd"
printf 'type octile\nheight 4\nwidth 8\nmap\n........\n........\n........\n........\n' >"$work/tiny.map"
out=$("$fleetctl" traffic-bench --mapd --map "$work/tiny.map" --pd "$work/tiny.map.pd" --agents 4 --tasks 30 \
  --frequency 0.5 --seed 1 --out "$work/mapd.json") || fail "mapd exited with $?"
for key in solved=1 service_time= makespan= comp_time_ms=; do
  grep -q "^$key" <<<"$out" || fail "mapd output lacks $key: $out"
done
python3 "$src/scripts/check-plan.py" "$work/tiny.map" "$work/mapd.json" --rotations || fail "mapd plan refused"

# Starts from a MovingAI .scen: agent i stands on row i's start and heads first for its goal.
smap=$src/tests/unit/planning/data/ost003d.map
scen=$src/tests/unit/planning/data/ost003d-random-1.scen
"$fleetctl" traffic-bench --map "$smap" --scen "$scen" --agents 50 --steps 60 --seed 2 \
  --out "$work/scen.json" >/dev/null || fail "traffic-bench --scen exited with $?"
python3 "$src/scripts/check-plan.py" "$smap" "$work/scen.json" --rotations >/dev/null || fail "scen plan refused"
python3 - "$scen" "$work/scen.json" <<'PY' || fail "starts or first goals differ from the .scen rows"
import json, sys
rows = [l.rstrip("\n").split("\t") for l in open(sys.argv[1]).readlines()[1:51]]
d = json.load(open(sys.argv[2]))
assert d["plan"][0] == [[int(r[4]), int(r[5])] for r in rows], "starts"
first = {a: g for t, a, g in d["goals"] if t == 0}
assert [first[i] for i in range(50)] == [[int(r[6]), int(r[7])] for r in rows], "first goals"
PY

expect2() {
  local what=$1
  shift
  local err
  err=$("$fleetctl" traffic-bench "$@" 2>&1 >/dev/null)
  local rc=$?
  [[ $rc == 2 ]] || fail "$what: exit code $rc, expected 2 ($err)"
  [[ -n $err ]] || fail "$what: no message"
  echo "ok ($what): $err" | head -n 1
}
expect2 "missing map" --map "$work/nope.map" --agents 5 --steps 5
expect2 "too many agents" --map "$work/tiny.map" --agents 33 --steps 5
expect2 "agents not a number" --map "$map" --agents many --steps 5
expect2 "zero steps" --map "$map" --agents 5 --steps 0
expect2 "mapd without pd" --map "$map" --mapd --agents 5
expect2 "bad pd" --map "$map" --mapd --pd "$work/tiny.map.pd" --agents 5
expect2 "bad frequency" --map "$work/tiny.map" --mapd --pd "$work/tiny.map.pd" --agents 2 --frequency -1
expect2 "too many mapd agents" --map "$work/tiny.map" --mapd --pd "$work/tiny.map.pd" --agents 5
expect2 "unknown rotations" --map "$map" --agents 5 --rotations sometimes
expect2 "scen of another map" --map "$work/tiny.map" --scen "$scen" --agents 2 --steps 5
expect2 "more agents than scen rows" --map "$smap" --scen "$scen" --agents 1001 --steps 5
expect2 "missing scen" --map "$smap" --scen "$work/nope.scen" --agents 2 --steps 5
expect2 "scen with mapd" --map "$work/tiny.map" --mapd --pd "$work/tiny.map.pd" --scen "$scen" --agents 2
echo PASS
