#!/usr/bin/env bash
# Wall adhesion of the seven-level study with independent seeds (/work/proof4), steps 3 and 4
# again with 8 runs per fit setting instead of 4: the same data, diagnosis, bounds, start and
# iterations as hidden_effect.sh. Tests whether the cone-angle miss (1.57x) is the fit's 4-run
# scatter.
set -euo pipefail
cd /work/main
tilth=/work/proof4/tilth cache=/work/proof4/cache
src=/work/proof4/hidden-wall_adhesion out=/work/proof6/hidden-wall_adhesion-r8
mkdir -p $out
cp $src/data.csv $src/conditions.csv $out/
top=$(python3 - "$src/2-diagnose/diagnosis.json" models/li2022.toml <<'PY'
import json, sys, tomllib
c = json.load(open(sys.argv[1]))["candidates"][0]
step = tomllib.load(open(sys.argv[2], "rb"))["candidates"][c["name"]]["step"]
est = max(c["strength"], 0.0)
print(c["name"], est, max(3 * est, 2 * step))
PY
)
read -r name est hi <<< "$top"
echo "=== fit $name from $est in [0, $hi], 8 runs per setting $(date)"
$tilth fit --model models/li2022.toml --data $out/data.csv --out $out/3-fit \
  --param soil-soil.rolling_friction=0.05:0.45 --param "candidate.$name=0:$hi@$est" \
  --replicates 8 --iterations 3 --coarse --quiet --cache $cache > /dev/null
$tilth compare --model $out/3-fit/model.toml --data $out/data.csv --out $out/4-compare \
  --replicates 16 --coarse --quiet --cache $cache > /dev/null
echo "=== done $(date)"
