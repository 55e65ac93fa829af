#!/usr/bin/env bash
# Sweep benchmarks for BENCHMARKS.md: the same 8-run sweep on 1 and on 2 cores, and the cost
# of recording (every channel at 50 frames per simulated second) against recording nothing.
# Run on a quiet machine: tools/bench/sweep.sh [OUT_DIR]
set -euo pipefail
cd "$(dirname "$0")/../.."
out="${1:-/tmp/tilth-sweep-bench}"
rm -rf "$out"
cargo build --release -p tilth >/dev/null
tilth=target/release/tilth
secs() { local t0 t1; t0=$(date +%s.%N); "$@" >/dev/null; t1=$(date +%s.%N); echo "$t1 - $t0" | bc -l; }
one=$(secs $tilth sweep run sweeps/bench/eight.toml --cores 1 --quiet --out "$out/one")
two=$(secs $tilth sweep run sweeps/bench/eight.toml --cores 2 --quiet --out "$out/two")
bare=$(secs $tilth sweep run sweeps/bench/eight_unrecorded.toml --cores 1 --quiet --out "$out/bare")
# Per-run stepping time summed over runs, from results.csv (column wall_seconds).
sum() { awk -F, 'NR == 1 { for (i = 1; i <= NF; i++) if ($i == "wall_seconds") c = i } NR > 1 { s += $c } END { printf "%.2f", s }' "$1/results.csv"; }
echo "8 runs, 1 core:             $(printf %.1f "$one") s wall (runs: $(sum "$out/one") s)"
echo "8 runs, 2 cores:            $(printf %.1f "$two") s wall (runs: $(sum "$out/two") s)"
echo "speed-up 1 -> 2 cores:      $(echo "$one / $two" | bc -l | xargs printf %.2f)x"
echo "8 runs, 1 core, unrecorded: $(printf %.1f "$bare") s wall (runs: $(sum "$out/bare") s)"
echo "cost of recording at 50 Hz: $(echo "100 * ($one - $bare) / $bare" | bc -l | xargs printf %.1f) % of the unrecorded sweep"
du -sh "$out/one/runs" | awk '{print "MCAP + summaries, 8 runs: " $1}'
