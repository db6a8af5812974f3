#!/usr/bin/env bash
# transport_bench plus ddsperf (Debian cyclonedds-tools) with the same loopback config, in one run.
# Usage: run.sh <transport_bench exe> <json out> [benchmark args]
set -euo pipefail
exe=$1; out=$2; shift 2
here=$(cd "$(dirname "$0")" && pwd)
export CYCLONEDDS_URI
CYCLONEDDS_URI="$(sed -n '/<CycloneDDS/,$p' "$here/../../../deploy/cyclonedds-local.xml")"
dom=$((100 + RANDOM % 100))
tmp=$(mktemp -d)
echo "-- ddsperf ping/pong, 256 B, waitset, domain $dom (8 s)"
timeout 15 ddsperf -i "$dom" -D 10 pong waitset >"$tmp/pong" 2>&1 &
sleep 0.5
timeout 15 ddsperf -i "$dom" -D 8 ping size 256 waitset >"$tmp/ping" 2>&1 || true
wait || true
# Median over the per-second lines (skip the first second: discovery and warm-up).
awk '/size 256 mean/ {for (i=1;i<=NF;i++) {if ($i=="50%") p50=$(i+1); if ($i=="99%") p99=$(i+1)}; n++; if (n>1) {print p50, p99}}' "$tmp/ping" \
  | sed 's/us//g' | sort -n | awk '{a[NR]=$1; b[NR]=$2} END {m=int((NR+1)/2); printf "ddsperf one-way p50 %.1f us, p99 (median of per-second p99) %.1f us over %d s\n", a[m], b[m], NR}' | tee "$tmp/ddsperf_latency"
echo "-- ddsperf pub/sub throughput, 256 B, reliable keep-all (6 s)"
timeout 12 ddsperf -i "$dom" -D 8 sub >"$tmp/sub" 2>&1 &
sleep 0.5
timeout 12 ddsperf -i "$dom" -D 6 -k all pub size 256 >"$tmp/pub" 2>&1 || true
wait || true
grep -E "size 256 total" "$tmp/sub" | tail -n 4 || tail -n 5 "$tmp/sub"
unset CYCLONEDDS_URI  # our wrapper uses its built-in loopback config (the same settings)
export FLEET_DDS_DOMAIN=$((dom + 1))
echo "-- transport_bench (our wrapper)"
"$exe" --benchmark_out="$out" --benchmark_out_format=json "$@"
rm -rf "$tmp"
