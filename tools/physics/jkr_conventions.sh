#!/usr/bin/env bash
# The study's funnel test under each JKR convention (docs/physics.md, "Cohesion: JKR"):
# models/li2022.toml as it is (`jkr`, EDEM's) and with `normal = "jkr_lammps"`, at each
# moisture, SEEDS seeds each, at the coarse preset (SCALE=--coarse; SCALE= for the study's
# 2 mm); prints each run's readings and the means with their standard errors. LAWS picks the
# conventions; JOBS runs that many at once, one thread each.
#
#   tools/physics/jkr_conventions.sh OUT [SEEDS]      # about 2 minutes at 8 seeds, coarse
set -euo pipefail
out=$1 seeds=${2:-8}
tilth=${TILTH:-target/release/tilth}
scale=${SCALE---coarse}
levels=${LEVELS:-3 6 9 12}
laws=${LAWS:-jkr jkr_lammps}
jobs=${JOBS:-1}
mkdir -p "$out"
out=$(cd "$out" && pwd)
cp models/li2022.toml "$out/li2022-jkr.toml"
sed 's/^normal = "jkr" /normal = "jkr_lammps"/' models/li2022.toml > "$out/li2022-jkr_lammps.toml"
grep -q '^normal = "jkr_lammps"' "$out/li2022-jkr_lammps.toml" || { echo "models/li2022.toml: no line 'normal = \"jkr\"'" >&2; exit 1; }
echo "law,moisture_pct,seed,heap_cone_angle_deg,tray_mass_g,funnel_flow_rate_g_s,funnel_residue_g" > "$out/runs.csv"
run_one() {  # LAW MOISTURE SEED: one run's readings as a CSV row
  local law=$1 m=$2 s=$3 exp=$out/$1-$2-$3.toml
  sed -e "s#^model = .*#model = \"$out/li2022-$law.toml\"#" -e "s#^moisture_pct = .*#moisture_pct = $m#" \
    -e "s#^seed = .*#seed = $s#" sweeps/experiments/repose.toml > "$exp"
  "$tilth" run "$exp" $scale --quiet --threads 1 --json --out "$out/runs/$law-$m-$s" |
    python3 -c "
import json, sys
r = json.load(sys.stdin)['experiment']
print('$law,$m,$s,' + ','.join(str(r[k]) for k in ['heap_cone_angle_deg', 'tray_mass_g', 'funnel_flow_rate_g_s', 'funnel_residue_g']))
"
}
export -f run_one
export out tilth scale
for law in $laws; do for m in $levels; do for s in $(seq 1 "$seeds"); do echo "$law $m $s"; done; done; done |
  xargs -P "$jobs" -L 1 bash -c 'run_one "$@"' _ | sort -t, -k1,1 -k2,2n -k3,3n >> "$out/runs.csv"
python3 - "$out/runs.csv" <<'PY'
import csv, statistics as st, sys
rows = list(csv.DictReader(open(sys.argv[1])))
keys = ["heap_cone_angle_deg", "tray_mass_g", "funnel_flow_rate_g_s", "funnel_residue_g"]
print("law, moisture: " + ", ".join(f"{k} mean (standard error)" for k in keys))
for law in dict.fromkeys(r["law"] for r in rows):
    for m in sorted({r["moisture_pct"] for r in rows}, key=float):
        rr = [r for r in rows if r["law"] == law and r["moisture_pct"] == m]
        cells = []
        for k in keys:
            v = [float(r[k]) for r in rr if r[k] not in ("", "None")]
            se = st.stdev(v) / len(v) ** 0.5 if len(v) > 1 else float("nan")
            cells.append(f"{st.mean(v):.1f} ({se:.1f})" if v else "- (jammed)")
        print(f"{law}, {m} %: " + ", ".join(cells))
PY
