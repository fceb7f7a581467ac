#!/usr/bin/env bash
# The real-data rows of BENCHMARKS.md's discovery table: for each channel of the MEMS thermal cycle,
# fit (T, rate(T)) on t < 3130 s, then `tcomp diagnose` with the final cooling as the verification
# run; for each gyro of the LSM6DSM cold ramp, fit (T) on t < 4000 s and diagnose with the rest.
# Prints each verdict with the held-out residual before and after the named feature.
# Usage (repository root): scripts/realdata_diagnose.sh [path/to/tcomp]
set -euo pipefail
TC=${1:-target/release/tcomp}
OUT=$(mktemp -d)
trap 'rm -rf "$OUT"' EXIT

# split FILE SPLIT_S PREFIX: rows before SPLIT_S to PREFIX-train.csv, the rest to PREFIX-verify.csv
split() {
  awk -F, -v tr="$3-train.csv" -v ve="$3-verify.csv" -v s="$2" \
    'NR == 1 { print > tr; print > ve; next } { print > ((($1 + 0) < s) ? tr : ve) }' "$1"
}

# diagnose PREFIX CHANNEL FEATURE...
diagnose() {
  local p=$1 ch=$2
  shift 2
  local feats=()
  for f in "$@"; do feats+=(--feature "$f"); done
  "$TC" fit --data "$p-train.csv" --target "$ch" "${feats[@]}" --out "$p-$ch.tcm" --quiet \
    > /dev/null 2>&1
  "$TC" diagnose --model "$p-$ch.tcm" --data "$p-train.csv" --verify "$p-verify.csv" \
    --json > "$p-$ch.json"
  python3 - "$(basename "$p") $ch" "$p-$ch.json" << 'PY'
import json, sys
d = json.load(open(sys.argv[2]))
d = d.get("diagnosis", d)
print(f"{sys.argv[1]:<24} {d.get('verdict')}: {d.get('verdict_text', '')}")
PY
}

split data/realdata/mems_thermal_cycle.csv 3130 "$OUT/mems"
for ch in gyro_x_rad_s gyro_y_rad_s gyro_z_rad_s acc_x_m_s2 acc_y_m_s2 acc_z_m_s2; do
  diagnose "$OUT/mems" "$ch" temp_imu_C 'rate(temp_imu_C)'
done
split data/realdata/lsm6dsm_tvac_cold_ramp.csv 4000 "$OUT/lsm6dsm"
for ch in gyro_x_rad_s gyro_y_rad_s gyro_z_rad_s; do
  diagnose "$OUT/lsm6dsm" "$ch" temp_lsm6dsm_C
done
