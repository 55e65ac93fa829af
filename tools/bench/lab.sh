#!/usr/bin/env bash
# The virtual lab's tests timed for BENCHMARKS.md: `tilth bench lab` (each instrument's run on
# 1 and 2 threads) and its table written between the page's bench-lab markers, with the host,
# the commit and the command. Run on a quiet machine:
#   tools/bench/lab.sh                        # coarse preset, about 2 minutes
#   tools/bench/lab.sh --scale study          # the study's scale: hours (the funnel alone, minutes a run)
#   tools/bench/lab.sh --scale both --rounds 3
set -euo pipefail
cd "$(dirname "$0")/../.."
cargo build --release -p tilth >/dev/null
table=$(target/release/tilth bench lab --quiet "$@")
echo "$table"
host=$(lscpu | sed -n 's/^Model name: *//p' | head -1)
block=$(mktemp)
{
    echo "<!-- bench-lab: written by tools/bench/lab.sh; do not edit by hand -->"
    commit=$(git rev-parse --short HEAD)$(git diff --quiet HEAD -- kernel runner tools || echo " with uncommitted changes")
    echo "\`tilth bench lab${*:+ $*}\` on $host ($(nproc) cores), tilth at \`$commit\`, $(date -u +%Y-%m-%d):"
    echo
    echo '```'
    echo "$table"
    echo '```'
    echo "<!-- /bench-lab -->"
} >"$block"
python3 - "$block" <<'PY'
import re, sys
block = open(sys.argv[1]).read().rstrip("\n")
page = open("BENCHMARKS.md").read()
pattern = re.compile(r"<!-- bench-lab:.*?<!-- /bench-lab -->", re.S)
if not pattern.search(page):
    sys.exit("BENCHMARKS.md: no bench-lab markers (<!-- bench-lab: ... --> ... <!-- /bench-lab -->) to write between")
open("BENCHMARKS.md", "w").write(pattern.sub(lambda _: block, page, count=1))
PY
rm -f "$block"
echo "BENCHMARKS.md: bench-lab table written"
