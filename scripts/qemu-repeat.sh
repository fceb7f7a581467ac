#!/usr/bin/env bash
# Runs `cargo xtask qemu` N times in a row (default 50) and prints one line per run and a tally:
# the QEMU replay and update steps must pass every time (BENCHMARKS.md records the result).
# Not part of CI: about a minute per run once built.
#   scripts/qemu-repeat.sh [N] [LOG_DIR]
set -uo pipefail
cd "$(dirname "$0")/.."
n=${1:-50}
logs=${2:-target/qemu-repeat}
mkdir -p "$logs"
cargo build -q -p xtask || exit 1
pass=0
fail=0
for i in $(seq 1 "$n"); do
  start=$(date +%s)
  # Each run is bounded inside the xtask (every QEMU run and child process has its limit); this
  # outer limit only catches a hang of the xtask itself.
  if timeout 1800 cargo xtask qemu >"$logs/run-$i.log" 2>&1; then
    pass=$((pass + 1))
    verdict=pass
  else
    fail=$((fail + 1))
    verdict="FAIL ($(grep -m1 -E '^Error|failed|killed' "$logs/run-$i.log" | head -c 200))"
  fi
  summary=$(grep -m1 -o 'update over the UART: committed[^;]*' "$logs/run-$i.log" | head -c 160)
  echo "run $i/$n: $verdict in $(($(date +%s) - start)) s; $summary"
done
echo "QEMU-REPEAT runs=$n passed=$pass failed=$fail (logs in $logs)"
[ "$fail" -eq 0 ]
