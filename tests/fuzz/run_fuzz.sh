#!/usr/bin/env bash
# ctest's fuzz.NAME: fuzzes TARGET for SECONDS starting from the repository's seeds (read only);
# new inputs go to WORKDIR/corpus, a crashing input to WORKDIR/crash-*.
# Usage: run_fuzz.sh TARGET SEED_DIR WORKDIR SECONDS
set -euo pipefail
target=$1 seeds=$2 work=$3 seconds=$4
mkdir -p "$work/corpus"
# -timeout: one input taking over 10 s is a finding (a hang); -rss_limit_mb: so is using 2 GB.
exec "$target" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 \
  -artifact_prefix="$work/" "$work/corpus" "$seeds"
