#!/usr/bin/env bash
# The discovery loop acting on the verdict (docs/discovery.md, "The verdict"): hide EFFECT at
# STRENGTH in the truth (EFFECT none: no effect), make the funnel test's data from it,
# diagnose; on `ambiguous`, rank the menu with `tilth next`, measure its best suggestion from
# the same truth (`synth`, the same seed), add it to the data and diagnose again; on `effect`,
# fit the model from the diagnosis and compare. Prints one line: the verdicts, the suggestion
# and whether the effect named is the hidden one.
#
#   tools/discovery/verdict_loop.sh EFFECT STRENGTH OUT [SEED]
#   tools/discovery/verdict_loop.sh plastic_adhesion 0.04 runs/loop-plastic 3
#
# Environment as hidden_effect.sh (setup.sh), and MENU (default models/li2022-menu.csv),
# NOISE_MORE (the injected noise of the readings the menu adds; default 4 % of the peak shear
# force and of the UCS, 2 deg of the outline-fit repose angle, 0.015 of the tilting plate's
# static friction and 0.5 deg of its angle: an inclinometer read to half a degree), SHIFT=PAIR.KEY=DELTA (moves
# a parameter of the truth, as null_study.sh), TRUTH_MODEL (the truth's model file, default
# the model's: a truth with an effect no candidate implements).
set -euo pipefail
effect=$1 strength=$2 out=$3 seed=${4:-1}
source "$(dirname "$0")/setup.sh"
menu=${MENU:-models/li2022-menu.csv}
noise_all="$NOISE,${NOISE_MORE:-peak_shear_force_n=4%,ucs_kpa=4%,repose_angle_deg=2,static_friction=0.015,slide_angle_deg=0.5}"
truth=()
[ "$effect" != none ] && truth+=(--with "$effect=$strength")
[ -n "${SHIFT:-}" ] && truth+=(--shift "$SHIFT")
lab=($SCALE $LAB --quiet --cache "$cache")

verdict_of() {
  python3 - "$1/diagnosis.json" <<'PY'
import json, sys
v = json.load(open(sys.argv[1]))["verdict"]
named = [e["name"] for e in v["effects"]]
print(v["verdict"], ",".join(named or v["ambiguous"]) or "-")
PY
}

"$tilth" synth --truth "${TRUTH_MODEL:-$model}" "${truth[@]}" --conditions "$out/conditions.csv" \
  --noise "$NOISE" --replicates "$R_DATA" --seed "$seed" --out "$out/data.csv" "${lab[@]}"
"$tilth" diagnose --model "$model" --data "$out/data.csv" --out "$out/2-diagnose" \
  --param "$FREE" --replicates "$R" $DIAGNOSE "${lab[@]}" > /dev/null
read -r first names <<< "$(verdict_of "$out/2-diagnose")"
line="$effect $strength seed $seed: $first $names"
final=$first final_names=$names
if [ "$first" = ambiguous ]; then
  # Scored as synth measures: the mean of R_DATA specimens.
  "$tilth" next --diagnosis "$out/2-diagnose" --menu "$menu" --out "$out/3-next" \
    --specimens "$R_DATA" "${lab[@]}" > /dev/null
  suggestion=$(tail -n +2 "$out/3-next/conditions.csv" | head -1 | cut -d, -f1-4)
  "$tilth" synth --truth "${TRUTH_MODEL:-$model}" "${truth[@]}" --conditions "$out/3-next/conditions.csv" \
    --noise "$noise_all" --replicates "$R_DATA" --seed "$seed" --out "$out/3-next/measured.csv" "${lab[@]}"
  cp "$out/data.csv" "$out/data-2.csv"
  tail -n +2 "$out/3-next/measured.csv" >> "$out/data-2.csv"
  "$tilth" diagnose --model "$model" --data "$out/data-2.csv" --out "$out/4-diagnose" \
    --param "$FREE" --replicates "$R" $DIAGNOSE "${lab[@]}" > /dev/null
  read -r final final_names <<< "$(verdict_of "$out/4-diagnose")"
  line="$line; next: $suggestion; then $final $final_names"
fi
if [ "$final" = effect ]; then
  diag=$out/2-diagnose
  [ -d "$out/4-diagnose" ] && diag=$out/4-diagnose data=$out/data-2.csv || data=$out/data.csv
  # With DIAGNOSE=--refit the diagnosis has fitted the named effect already.
  refitted=$diag/refit/$final_names
  if [ -f "$refitted/fit.json" ]; then
    mkdir -p "$out/5-fit" && cp "$refitted"/fit.json "$refitted"/fit.md "$refitted"/model.toml "$out/5-fit/"
  else
    "$tilth" fit --model "$model" --data "$data" --from-diagnosis "$diag" --out "$out/5-fit" \
      --replicates "$R" --iterations 3 "${lab[@]}" > /dev/null
  fi
  "$tilth" compare --model "$out/5-fit/model.toml" --data "$data" --out "$out/6-compare" \
    --replicates "$R_JUDGE" "${lab[@]}" > /dev/null
  line="$line; fitted $(python3 -c "import json,sys; f=json.load(open(sys.argv[1])); print(' '.join(f'{p[\"label\"]}={e:.4f}±{s or 0:.4f}' for p,e,s in zip(f['parameters'],f['estimate'],f['standard_error'])), 'chi2 %.1f dof %d' % (f['chi2'], f['dof']))" "$out/5-fit/fit.json")"
fi
case "$final $final_names" in
  "effect $effect" | "no_effect -") [ "$effect" = none ] || [ "$final" = effect ] && right=right || right=unnamed ;;
  effect*) right=WRONG ;;
  *) right=unnamed ;;
esac
echo "$line [$right]"
