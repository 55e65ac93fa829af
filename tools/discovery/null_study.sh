#!/usr/bin/env bash
# The discovery loop's false-alarm rate (docs/discovery-proof.md, "No hidden effect"): data made by
# the model itself (truth = model + noise) for SEEDS seeds, each diagnosed; counts the seeds
# in which some candidate is called significant. The model's runs are the same for every
# seed and come from one cache (--cache), so each seed costs only its truth runs.
#
#   tools/discovery/null_study.sh OUT [SEEDS]
#   tools/discovery/null_study.sh runs/null 20
#
# Environment: TILTH, MODEL, SCALE, LAB, R, NOISE, FREE as in hidden_effect.sh; CACHE (default
# OUT/cache); SHIFT=PAIR.KEY=DELTA (optional) moves a parameter of the truth (`tilth synth
# --shift`), so that the model is off where FREE can absorb it, with no effect hidden
# (docs/discovery-proof.md, "A free parameter off"):
#
#   SHIFT=soil-soil.rolling_friction=0.05 tools/discovery/null_study.sh runs/null-off 20
#
# PARAM_STEP (optional): diagnose's --param-step (default 0.05).
set -euo pipefail
out=$1 seeds=${2:-20}
source "$(dirname "$0")/setup.sh"
shift_truth=()
[ -n "${SHIFT:-}" ] && shift_truth=(--shift "$SHIFT")
for s in $(seq 1 "$seeds"); do
  "$tilth" synth --truth "$model" "${shift_truth[@]}" --conditions "$out/conditions.csv" --noise "$NOISE" \
    --replicates "$R" --seed "$s" --out "$out/seed-$s/data.csv" $SCALE $LAB --quiet --cache "$cache"
  "$tilth" diagnose --model "$model" --data "$out/seed-$s/data.csv" --out "$out/seed-$s/diagnose" \
    --param "$FREE" --replicates "$R" --no-refit ${PARAM_STEP:+--param-step "$PARAM_STEP"} $DIAGNOSE $SCALE $LAB --quiet --cache "$cache" > /dev/null
done
python3 - "$out" "$seeds" <<'PY'
import json, sys
out, seeds = sys.argv[1], int(sys.argv[2])
flagged = 0
print("seed  first candidate  statistic  p (Holm)  significant")
for s in range(1, seeds + 1):
    c = json.load(open(f"{out}/seed-{s}/diagnose/diagnosis.json"))["candidates"]
    hit = [x["name"] for x in c if x["significant"]]
    flagged += bool(hit)
    print(f"{s:4d}  {c[0]['name']:<16} {c[0]['statistic']:9.2f}  {c[0]['p_value']:8.3g}  {', '.join(hit) or '-'}")
print(f"seeds with a significant candidate: {flagged} of {seeds}")
PY
