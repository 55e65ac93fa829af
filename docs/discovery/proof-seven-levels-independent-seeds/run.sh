#!/usr/bin/env bash
# Fourth study (2026-11-26): the seven-level study again with each condition's seeds derived
# from the replicate and the condition (7b9186a) and fit's score stop rule (0932f0c).
# Nothing else changed: same levels, noise, strengths, synth seeds, replicates.
cd /work/main && git rev-parse HEAD   # printed 523a56c
export TILTH=/work/proof4/tilth CACHE=/work/proof4/cache
export R_DATA=16 R_JUDGE=16 TRUTH=1 LEVELS="3 4.5 6 7.5 9 10.5 12"
export NOISE=heap_cone_angle_deg=1.1,tray_mass_g=0.5,funnel_flow_rate_g_s=2%,funnel_residue_g=0.05
for e in "plastic_adhesion 0.04 3" "wall_adhesion 0.02 2" "fines 0.15 1"; do
  set -- $e
  echo "=== $1 $(date)"
  bash tools/discovery/hidden_effect.sh $1 $2 /work/proof4/hidden-$1 $3 2>&1
done
echo "=== done $(date)"
