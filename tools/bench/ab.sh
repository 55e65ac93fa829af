#!/usr/bin/env bash
# A against B on the settling bed, alternating, in one sitting: two builds of tilth (for
# example main and a branch, each built with `cargo build --release -p tilth` and copied out),
# each run on 1 and 2 threads, ROUNDS times, then LIGGGHTS once if installed. Prints each
# run's state hash (the builds must agree to the bit) and particle-steps/s.
#
#   tools/bench/ab.sh OLD_TILTH NEW_TILTH            # N=20000 S=20000 ROUNDS=2 COHESION=sjkr
set -euo pipefail
old=$1 new=$2
N=${N:-20000}; S=${S:-20000}; ROUNDS=${ROUNDS:-2}; COHESION=${COHESION:-sjkr}
DECK=${DECK:-$(cd "$(dirname "$0")/settling-bed" && pwd)}
echo "settling bed A/B: $N particles, $S steps, --cohesion $COHESION, $(date -u +%H:%M:%S) UTC"
for round in $(seq "$ROUNDS"); do
  for t in 1 2; do
    for b in "$old" "$new"; do
      out=$("$b" bench settling-bed --particles "$N" --steps "$S" --threads "$t" --cohesion "$COHESION" --quiet 2>&1)
      echo "round $round, $b, $t thread(s): $(echo "$out" | grep -i "state hash") | $(echo "$out" | tail -1)"
    done
  done
done
if command -v liggghts >/dev/null && [ -n "$DECK" ]; then
  work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
  (cd "$work" && liggghts -in "$DECK/bed.liggghts" -var npart "$N" -var nsteps "$S" -log none > liggghts.out 2>&1)
  echo "LIGGGHTS: $(grep -E '^Loop time of' "$work/liggghts.out" | tail -1)"
fi
