#!/usr/bin/env bash
# The discovery loop on data with a hidden effect, at the coarse preset (docs/discovery-proof.md,
# "The proof"): hide candidate EFFECT at STRENGTH in the truth, make funnel-test data from
# it, compare the model (which lacks it), diagnose, fit the model with the top candidate's
# strength free, compare again, and write the project's report.
#
#   tools/discovery/hidden_effect.sh EFFECT STRENGTH OUT [SEED]
#   tools/discovery/hidden_effect.sh plastic_adhesion 0.05 runs/hidden-plastic
#
# The data: the funnel test at LEVELS % moisture (3, 6, 9, 12), four readings each (fixed-base
# cone angle, tray mass, flow rate, soil left in the funnel), each value the mean of R_DATA
# truth runs plus the injected noise. The error after the fit is printed against the data's
# noise (the RMS of their `uncertainty`: the injected noise and the scatter of the truth's
# mean) and against the injected noise alone.
#
# Environment: TILTH (the binary; default target/release/tilth), MODEL (default
# models/li2022.toml), SCALE (default --coarse; empty: the study's scale), LAB (more options
# for every command: "--slurm" runs each batch of runs as a Slurm job array), R, R_DATA and
# R_JUDGE (replicates), NOISE (the injected noise) and LEVELS (the moisture levels) as
# setup.sh says, FREE (the model's free parameter), TRUTH=1 (also compare the truth itself
# with the data, R_JUDGE runs per condition, in OUT/5-truth: the error a perfect fit would
# leave on these data, which the fitted model's is read against), CACHE
# (the run cache, default OUT/cache: give several studies of one model the same cache and
# they share the model's runs).
set -euo pipefail
effect=$1 strength=$2 out=$3 seed=${4:-1}
source "$(dirname "$0")/setup.sh"

"$tilth" synth --truth "$model" --with "$effect=$strength" --conditions "$out/conditions.csv" \
  --noise "$NOISE" --replicates "$R_DATA" --seed "$seed" --out "$out/data.csv" $SCALE $LAB --quiet --cache "$cache"
"$tilth" compare --model "$model" --data "$out/data.csv" --out "$out/1-compare" \
  --replicates "$R_JUDGE" $SCALE $LAB --quiet --cache "$cache" > /dev/null
"$tilth" diagnose --model "$model" --data "$out/data.csv" --out "$out/2-diagnose" \
  --param "$FREE" --replicates "$R" --no-refit $DIAGNOSE $SCALE $LAB --quiet --cache "$cache" > /dev/null
# The first candidate's strength, free in [0, max(3 x its estimate, 2 x its step)] from the
# estimate: what a user knows after the diagnosis (the hidden strength is not used).
top=$(python3 - "$out/2-diagnose/diagnosis.json" "$model" <<'PY'
import json, sys, tomllib
c = json.load(open(sys.argv[1]))["candidates"][0]
step = tomllib.load(open(sys.argv[2], "rb"))["candidates"][c["name"]]["step"]
est = max(c["strength"], 0.0)
print(c["name"], est, max(3 * est, 2 * step), c["significant"])
PY
)
read -r name est hi significant <<< "$top"
echo "diagnose: first $name (strength $est, significant: $significant); hidden: $effect"
"$tilth" fit --model "$model" --data "$out/data.csv" --out "$out/3-fit" \
  --param "$FREE" --param "candidate.$name=0:$hi@$est" \
  --replicates "$R" --iterations 3 $SCALE $LAB --quiet --cache "$cache" > /dev/null
"$tilth" compare --model "$out/3-fit/model.toml" --data "$out/data.csv" --out "$out/4-compare" \
  --replicates "$R_JUDGE" $SCALE $LAB --quiet --cache "$cache" > /dev/null
if [ "${TRUTH:-0}" = 1 ]; then
  "$tilth" compare --model "$out/data.truth.toml" --data "$out/data.csv" --out "$out/5-truth" \
    --replicates "$R_JUDGE" $SCALE $LAB --quiet --cache "$cache" > /dev/null
fi
"$tilth" report "$out" > /dev/null
python3 "$(dirname "$0")/tables.py" --one "$out" "$NOISE"
