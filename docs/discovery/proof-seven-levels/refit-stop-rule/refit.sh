#!/usr/bin/env bash
# Re-run steps 3 (fit) and 4 (compare) of the seven-level study (/work/proof2) with fit's new
# stop rule (2026-11-26): same data, same diagnosis, same arguments as hidden_effect.sh.
set -euo pipefail
cd /work/main
tilth=/work/main/target/release/tilth
cache=/work/proof3/cache
for effect in "$@"; do
  src=/work/proof2/hidden-$effect out=/work/proof3/hidden-$effect
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
  echo "=== $effect: fit $name from $est in [0, $hi] $(date)"
  $tilth fit --model models/li2022.toml --data $out/data.csv --out $out/3-fit \
    --param soil-soil.rolling_friction=0.05:0.45 --param "candidate.$name=0:$hi@$est" \
    --replicates 4 --iterations 3 --coarse --quiet --cache $cache > /dev/null
  $tilth compare --model $out/3-fit/model.toml --data $out/data.csv --out $out/4-compare \
    --replicates 16 --coarse --quiet --cache $cache > /dev/null
  echo "=== $effect done $(date)"
done
