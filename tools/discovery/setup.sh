# The set-up both discovery scripts share (sourced with OUT in $out): the defaults of their
# environment and the measured conditions, the funnel test at LEVELS % moisture (default 3, 6,
# 9 and 12) with four readings each, written to OUT/conditions.csv.
tilth=${TILTH:-target/release/tilth}
# Replicates: R model runs per setting in diagnose and fit; R_DATA truth runs averaged into
# each synthetic value and R_JUDGE model runs per condition in the two compares (both R unless
# set: docs/discovery-proof.md, "Judged against the injected noise alone", sets them to 16).
R=${R:-4}
R_DATA=${R_DATA:-$R}
R_JUDGE=${R_JUDGE:-$R}
# More options for every `tilth diagnose`, e.g. DIAGNOSE=--fit-first: fit the free
# parameters to the data first and score the candidates there.
DIAGNOSE=${DIAGNOSE:-}
# The injected noise (`tilth synth --noise`).
NOISE=${NOISE:-heap_cone_angle_deg=0.5,tray_mass_g=0.5,funnel_flow_rate_g_s=2%,funnel_residue_g=0.05}
FREE=${FREE:-soil-soil.rolling_friction=0.05:0.45}
model=${MODEL:-models/li2022.toml}
SCALE=${SCALE---coarse}   # SCALE= (empty) runs at the study's scale
# More options for every tilth command that runs the lab tests: LAB="--slurm --slurm-time 4:00:00"
# makes each batch of runs a Slurm job array (the out and cache directories on shared storage).
LAB=${LAB:-}
cache=${CACHE:-$out/cache}
# The moisture levels (%, space-separated). More levels make each reading's RMSE a steadier
# number: over n rows a model that is the truth itself exceeds 1.5x the noise with the chance
# P(chi^2_n > 2.25 n), 6 % at n = 4 and 3 % at n = 7 (docs/discovery-proof.md, "Judged against the injected noise alone").
LEVELS=${LEVELS:-3 6 9 12}
mkdir -p "$out"
{
  echo "test,moisture_pct,observable"
  for m in $LEVELS; do
    for o in heap_cone_angle_deg tray_mass_g funnel_flow_rate_g_s funnel_residue_g; do echo "repose,$m,$o"; done
  done
} > "$out/conditions.csv"
