#!/usr/bin/env bash
# The real-data rows of BENCHMARKS.md's discovery table: for each channel of the MEMS thermal cycle,
# fit (T, rate(T)) on t < 3130 s, then `tcomp diagnose` with the final cooling as the verification
# run, and print the verdict with the held-out residual before and after the named feature.
# Usage (repository root): scripts/realdata_diagnose.sh [path/to/tcomp]
set -euo pipefail
TC=${1:-target/release/tcomp}
DATA=data/realdata/mems_thermal_cycle.csv
OUT=$(mktemp -d)
trap 'rm -rf "$OUT"' EXIT
awk -F, -v out="$OUT" 'NR == 1 { print > (out "/train.csv"); print > (out "/verify.csv"); next }
    { print > ((($1 + 0) < 3130) ? out "/train.csv" : out "/verify.csv") }' "$DATA"
for ch in gyro_x_rad_s gyro_y_rad_s gyro_z_rad_s acc_x_m_s2 acc_y_m_s2 acc_z_m_s2; do
  "$TC" fit --data "$OUT/train.csv" --target "$ch" --feature temp_imu_C \
    --feature 'rate(temp_imu_C)' --out "$OUT/$ch.tcm" --quiet > /dev/null
  "$TC" diagnose --model "$OUT/$ch.tcm" --data "$OUT/train.csv" --verify "$OUT/verify.csv" \
    --json > "$OUT/$ch.json"
  python3 - "$ch" "$OUT/$ch.json" <<'EOF'
import json, sys
d = json.load(open(sys.argv[2]))
d = d.get("diagnosis", d)
print(f"{sys.argv[1]:<14} {d.get('verdict')}: {d.get('verdict_text', '')}")
EOF
done
