#!/usr/bin/env bash
# One unit of a production line per Slurm array task, then the fleet page once all have finished:
#
#   tcomp simulate --preset qma --units 1000 --outliers 5 --out units     # or the line's real logs
#   n=$(find units -mindepth 1 -maxdepth 1 -type d -name 'unit-*' | wc -l)
#   job=$(sbatch --parsable --array=0-$((n - 1))%100 examples/calibrate/slurm-array.sh \
#         examples/calibrate/fleet.calibrate.toml units cal)
#   sbatch --dependency=afterok:"$job" --wrap \
#         "tcomp calibrate examples/calibrate/fleet.calibrate.toml --collect cal --out cal"
#
# Each task runs the same `tcomp calibrate` as on one machine, on its own unit folder (the N-th in
# name order), and writes cal/unit-NNNN/ (blobs, image.bin, report.html, summary.json); the last
# job reads every summary.json and writes cal/fleet.html and cal/fleet.json with the outliers.
# Outside Slurm the same script runs one task: SLURM_ARRAY_TASK_ID=3 bash slurm-array.sh SPEC UNITS OUT
#SBATCH --job-name=tcomp-calibrate
#SBATCH --cpus-per-task=2
#SBATCH --mem=1G
#SBATCH --time=00:15:00
#SBATCH --output=tcomp-calibrate-%A_%a.log
set -euo pipefail

spec=${1:?usage: slurm-array.sh SPEC.toml UNITS_DIR OUT_DIR}
units=${2:?usage: slurm-array.sh SPEC.toml UNITS_DIR OUT_DIR}
out=${3:?usage: slurm-array.sh SPEC.toml UNITS_DIR OUT_DIR}
task=${SLURM_ARRAY_TASK_ID:?not an array task: set SLURM_ARRAY_TASK_ID}
tcomp=${TCOMP:-tcomp}

mapfile -t all < <(find "$units" -mindepth 1 -maxdepth 1 -type d -name 'unit-*' | sort)
if (( task >= ${#all[@]} )); then
    echo "task $task: only ${#all[@]} units in $units" >&2
    exit 1
fi
unit=${all[$task]}
mkdir -p "$out"
exec "$tcomp" calibrate "$spec" --unit "$unit" --out "$out/$(basename "$unit")" --quiet
