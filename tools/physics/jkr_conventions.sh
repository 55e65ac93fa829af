#!/usr/bin/env bash
# The study's funnel test under each JKR convention (docs/physics.md, "Cohesion: JKR"):
# models/li2022.toml as it is (`jkr`, EDEM's) and with `normal = "jkr_lammps"`, at each
# moisture, SEEDS seeds each, at the coarse preset (SCALE=--coarse; SCALE= for the study's
# 2 mm); prints each run's readings and the means with their standard errors.
#
#   tools/physics/jkr_conventions.sh OUT [SEEDS]      # about 2 minutes at 8 seeds, coarse
set -euo pipefail
out=$1 seeds=${2:-8}
tilth=${TILTH:-target/release/tilth}
scale=${SCALE---coarse}
levels=${LEVELS:-3 6 9 12}
mkdir -p "$out"
out=$(cd "$out" && pwd)
cp models/li2022.toml "$out/li2022-jkr.toml"
sed 's/^normal = "jkr" /normal = "jkr_lammps"/' models/li2022.toml > "$out/li2022-jkr_lammps.toml"
grep -q '^normal = "jkr_lammps"' "$out/li2022-jkr_lammps.toml" || { echo "models/li2022.toml: no line 'normal = \"jkr\"'" >&2; exit 1; }
echo "law,moisture_pct,seed,heap_cone_angle_deg,tray_mass_g,funnel_flow_rate_g_s,funnel_residue_g" > "$out/runs.csv"
for law in jkr jkr_lammps; do
  for m in $levels; do
    for s in $(seq 1 "$seeds"); do
      exp=$out/$law-$m-$s.toml
      sed -e "s#^model = .*#model = \"$out/li2022-$law.toml\"#" -e "s#^moisture_pct = .*#moisture_pct = $m#" \
        -e "s#^seed = .*#seed = $s#" sweeps/experiments/repose.toml > "$exp"
      "$tilth" run "$exp" $scale --quiet --threads 1 --json --out "$out/runs/$law-$m-$s" |
        python3 -c "
import json, sys
r = json.load(sys.stdin)['experiment']
print('$law,$m,$s,' + ','.join(str(r[k]) for k in ['heap_cone_angle_deg', 'tray_mass_g', 'funnel_flow_rate_g_s', 'funnel_residue_g']))
" >> "$out/runs.csv"
    done
  done
done
python3 - "$out/runs.csv" <<'PY'
import csv, statistics as st, sys
rows = list(csv.DictReader(open(sys.argv[1])))
keys = ["heap_cone_angle_deg", "tray_mass_g", "funnel_flow_rate_g_s"]
print("law, moisture: " + ", ".join(f"{k} mean (standard error)" for k in keys))
for law in ["jkr", "jkr_lammps"]:
    for m in sorted({r["moisture_pct"] for r in rows}, key=float):
        rr = [r for r in rows if r["law"] == law and r["moisture_pct"] == m]
        cells = []
        for k in keys:
            v = [float(r[k]) for r in rr if r[k] not in ("", "None")]
            se = st.stdev(v) / len(v) ** 0.5 if len(v) > 1 else float("nan")
            cells.append(f"{st.mean(v):.1f} ({se:.1f})" if v else "- (jammed)")
        print(f"{law}, {m} %: " + ", ".join(cells))
PY
