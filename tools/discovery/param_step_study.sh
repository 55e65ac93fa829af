#!/usr/bin/env bash
# Diagnoses every draw of a finished discovery proof again with another free-parameter step
# (docs/discovery-proof.md, "The free parameters' step in `diagnose`"): the proof's hidden-effect
# draws (PROOF/rate-*/seed*) and null seeds (PROOF/null/seed-*), each into SUB beside its
# own diagnosis, with `--param-step STEP` and the proof's settings, sharing the proof's run
# cache, so that only the free parameter's runs are new. Then summarise with
# tools/discovery/param_step_table.py.
#
#   tools/discovery/param_step_study.sh PROOF STEP SUB
#   tools/discovery/param_step_study.sh target/tmp/discovery-proof 0.25 diagnose-25
#
# PROOF: a proof's scratch directory (`cargo test --release -p tilth --test runner
# discovery_proof` leaves it in target/tmp/discovery-proof). Environment as setup.sh (TILTH,
# MODEL, SCALE, LAB, R, FREE); they must be the proof's for its cache to serve.
set -euo pipefail
proof=$1 step=$2 sub=$3
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
source "$(dirname "$0")/setup.sh"
for dir in "$proof"/rate-*/seed* "$proof"/null/seed-*; do
  [ -f "$dir/$sub/diagnosis.json" ] && continue
  "$tilth" diagnose --model "$model" --data "$dir/data.csv" --out "$dir/$sub" \
    --param "$FREE" --param-step "$step" --replicates "$R" --no-refit $DIAGNOSE $SCALE $LAB --quiet \
    --cache "$proof/cache" > /dev/null
  echo "$dir/$sub"
done
