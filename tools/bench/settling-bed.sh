#!/usr/bin/env bash
# The settling-bed speed benchmark (tools/bench/settling-bed/README.md), run in tilth,
# LIGGGHTS and LAMMPS in one sitting on this machine; prints particle-steps/s and the ratios
# that BENCHMARKS.md records. Peers: apt-get install -y liggghts lammps (not needed by CI).
# Each peer is compared with tilth running its deck's cohesion: LIGGGHTS's simplified JKR
# (`--cohesion sjkr`) and LAMMPS's full JKR (`--cohesion jkr`, tilth's default).
#
#   tools/bench/settling-bed.sh            # N=20000 particles, S=20000 steps
#   N=20000 S=5000 tools/bench/settling-bed.sh
#   ROUNDS=3 tools/bench/settling-bed.sh   # each tilth run three times, ratios of the medians
set -euo pipefail
cd "$(dirname "$0")/../.."
N=${N:-20000}
S=${S:-20000}
# Rounds of the four tilth runs and the two peers, alternating; the ratios use each run's
# median. Two-thread speed on a VM depends on how the host schedules its two virtual CPUs,
# and the whole machine's speed drifts by up to a quarter within an hour, so a single round
# can land anywhere in that spread; the peers run in every round so that a slow spell slows
# both sides.
ROUNDS=${ROUNDS:-1}
DECK=${DECK:-$PWD/tools/bench/settling-bed}
cargo build --release -q -p tilth
TILTH=$PWD/target/release/tilth
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

rate() { awk -v n="$N" -v s="$S" -v t="$1" 'BEGIN { printf "%.4g", n * s / t }'; }
loop_time() { grep -E "^Loop time of" "$1" | tail -1 | awk '{print $4}'; }

echo "settling bed: $N particles, $S steps, $(date -u +%Y-%m-%dT%H:%MZ), $(nproc) cores"
declare -A R RUNS
for round in $(seq "$ROUNDS"); do
  for c in sjkr jkr; do
    for t in 1 2; do
      "$TILTH" bench settling-bed --particles "$N" --steps "$S" --threads "$t" --cohesion "$c" --quiet > "$work/tilth-$c$t.out"
      r=$(tail -1 "$work/tilth-$c$t.out" | awk '{print $2}')
      RUNS[$c$t]="${RUNS[$c$t]:-} $r"
      echo "tilth --cohesion $c, ${t} thread(s), round $round: $r particle-steps/s"
    done
  done
  if command -v liggghts >/dev/null; then
    (cd "$work" && liggghts -in "$DECK/bed.liggghts" -var npart "$N" -var nsteps "$S" -log none > liggghts.out 2>&1)
    r=$(rate "$(loop_time "$work/liggghts.out")")
    RUNS[liggghts]="${RUNS[liggghts]:-} $r"
    echo "LIGGGHTS, round $round: $r particle-steps/s (loop time $(loop_time "$work/liggghts.out") s)"
  fi
  if command -v lmp >/dev/null; then
    (cd "$work" && lmp -in "$DECK/bed.lammps" -var npart "$N" -var nsteps "$S" -log none > lammps.out 2>&1)
    r=$(rate "$(loop_time "$work/lammps.out")")
    RUNS[lammps]="${RUNS[lammps]:-} $r"
    echo "LAMMPS, round $round: $r particle-steps/s (loop time $(loop_time "$work/lammps.out") s)"
  fi
done
# The median of the rounds (the mean of the middle two for an even count).
median() { tr ' ' '\n' | grep . | sort -g | awk '{ v[NR] = $1 } END { m = int((NR + 1) / 2); printf "%.4g", (NR % 2) ? v[m] : (v[m] + v[m + 1]) / 2 }'; }
for k in sjkr1 sjkr2 jkr1 jkr2 liggghts lammps; do
  [ -n "${RUNS[$k]:-}" ] && R[$k]=$(echo "${RUNS[$k]}" | median)
done
[ "$ROUNDS" -gt 1 ] && for c in sjkr jkr; do for t in 1 2; do echo "tilth --cohesion $c, ${t} thread(s), median of $ROUNDS: ${R[$c$t]} particle-steps/s"; done; done
[ -n "${R[liggghts]:-}" ] && echo "LIGGGHTS, median of $ROUNDS: ${R[liggghts]} particle-steps/s"
[ -n "${R[lammps]:-}" ] && echo "LAMMPS, median of $ROUNDS: ${R[lammps]} particle-steps/s"
# Where each code's loop time went (tilth: its last round), side by side with the peers' own
# breakdowns (LIGGGHTS: Pair/Neigh/Comm/Outpt/Other; LAMMPS: its timing table).
for c in sjkr jkr; do
  echo "tilth --cohesion $c, 1 thread, time per part of the stepping loop:"
  sed -n '/^time per part/,/^  other/p' "$work/tilth-${c}1.out" | tail -n +2
done
[ -f "$work/liggghts.out" ] && { echo "LIGGGHTS, time per part of the loop:"; grep -E "^(Pair|Neigh|Comm|Outpt|Modify|Other) +time" "$work/liggghts.out" | tail -5 | sed 's/^/  /'; }
[ -f "$work/lammps.out" ] && { echo "LAMMPS, time per part of the loop:"; grep -E "^(Pair|Neigh|Comm|Output|Modify|Other) +\|" "$work/lammps.out" | tail -6 | sed 's/^/  /'; }
for c in sjkr jkr; do
  awk -v a="${R[${c}1]}" -v b="${R[${c}2]}" -v c="$c" 'BEGIN { printf "tilth (%s) speed-up 1 -> 2 threads: %.2fx\n", c, b / a }'
done
[ -n "${R[liggghts]:-}" ] && awk -v a="${R[sjkr1]}" -v l="${R[liggghts]}" 'BEGIN { printf "tilth (sjkr, 1 thread) / LIGGGHTS: %.2fx\n", a / l }'
[ -n "${R[lammps]:-}" ] && awk -v a="${R[jkr1]}" -v l="${R[lammps]}" 'BEGIN { printf "tilth (jkr, 1 thread) / LAMMPS: %.2fx\n", a / l }'
exit 0
