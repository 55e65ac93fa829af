#!/usr/bin/env bash
# How often `diagnose` finds a hidden effect, over draws of the data (docs/discovery-proof.md, "How
# often a hidden effect is ranked first"): for each SEED, `tilth synth` hides EFFECT at
# STRENGTH in the truth and draws the data with that seed, then `tilth diagnose` ranks the
# candidates, exactly as tools/discovery/hidden_effect.sh does (same conditions, replicates,
# noise and free parameter; no fit). Prints one line per seed and the count ranked first and
# significant. The model's own runs are cached in OUT/cache, so each seed after the first
# costs the truth's runs only (15-60 s a seed at the coarse preset on two cores).
#
#   tools/discovery/detection_rate.sh EFFECT STRENGTH OUT SEED...
#   tools/discovery/detection_rate.sh plastic_adhesion 0.04 runs/rate $(seq 3 18)
#
# Environment as hidden_effect.sh (TILTH, MODEL, SCALE, LAB, R, R_DATA, NOISE, LEVELS, FREE,
# CACHE).
set -euo pipefail
effect=$1 strength=$2 out=$3
shift 3
source "$(dirname "$0")/setup.sh"
first=0 total=0
for seed in "$@"; do
  dir="$out/seed$seed"
  mkdir -p "$dir"
  cp "$out/conditions.csv" "$dir/conditions.csv"
  "$tilth" synth --truth "$model" --with "$effect=$strength" --conditions "$dir/conditions.csv" \
    --noise "$NOISE" --replicates "$R_DATA" --seed "$seed" --out "$dir/data.csv" $SCALE $LAB --quiet --cache "$cache" > /dev/null
  "$tilth" diagnose --model "$model" --data "$dir/data.csv" --out "$dir/2-diagnose" \
    --param "$FREE" --replicates "$R" --no-refit $DIAGNOSE $SCALE $LAB --quiet --cache "$cache" > /dev/null
  line=$(python3 - "$dir/2-diagnose/diagnosis.json" "$seed" "$effect" <<'PY'
import json, sys
c = json.load(open(sys.argv[1]))["candidates"]
top, second = c[0], c[1]
hit = int(top["name"] == sys.argv[3] and top["significant"])
print(hit, f"seed {sys.argv[2]}: first {top['name']} (statistic {top['statistic']:.1f}, "
      f"p {top['p_value']:.2g}, strength {top['strength']:.4f}), second {second['name']} "
      f"(p {second['p_value']:.2g})")
PY
  )
  echo "${line#* }"
  first=$((first + ${line%% *}))
  total=$((total + 1))
done
echo "$effect at $strength: ranked first and significant in $first of $total draws"
