#!/usr/bin/env bash
# Mutation testing of the core and of the trainer's evidence/bayes modules: the runs behind the
# mutation scores in BENCHMARKS.md. Needs `cargo install cargo-mutants --locked`.
#
# Why these arguments:
# * the core's tests are fast; `--tests` leaves out the doctests, which would compile one binary per
#   example for every mutant and catch nothing the unit and integration tests do not;
# * the trainer's crate is built at opt-level 2 by the workspace profile, which makes every mutant a
#   multi-minute build; at opt-level 0 (floating point is IEEE either way, so results are the same)
#   a mutant builds in seconds. `--lib` as a cargo argument keeps the build phase to the unit tests
#   too (cargo-mutants otherwise builds every integration test of the crate for every mutant), and
#   the two fast integration tests written against these modules are added by name;
# * `--copy-target` reuses the dependencies already built in ./target; one job, two cores.
#
# Usage (repository root): scripts/mutants.sh core|train [extra cargo-mutants arguments]
# e.g. `scripts/mutants.sh core --in-diff my.diff`, `scripts/mutants.sh train --shard 0/8`.
# Results go to target/mutants-<which>/mutants.out (missed.txt, caught.txt, timeout.txt, unviable.txt).
set -euo pipefail
which=${1:?usage: scripts/mutants.sh core|train [cargo-mutants arguments]}
shift
common=(--jobs 1 --copy-target true --build-timeout 600 -o "target/mutants-$which")
case "$which" in
  core)
    cargo mutants -p tcomp-core "${common[@]}" "$@" -- --tests
    ;;
  train)
    cargo mutants -p tcomp-train -f crates/train/src/evidence.rs -f crates/train/src/bayes.rs \
      "${common[@]}" --sharding round-robin \
      --cargo-arg=--config=profile.dev.package.tcomp-train.opt-level=0 \
      --cargo-arg=--lib --cargo-arg=--test=mutants_evidence --cargo-arg=--test=mutants_bayes "$@"
    ;;
  *)
    echo "unknown target $which (core or train)" >&2
    exit 2
    ;;
esac
