#!/usr/bin/env bash
# The repository reads like a tool, not a lab notebook: page sizes, no patches of abandoned
# experiments, no comments that cite a dated attempt, docs/ small. Fails naming what is over.
set -euo pipefail
cd "$(dirname "$0")/.."
fail=0
over() { echo "$1"; fail=1; }
lines() { wc -l < "$1"; }
[ "$(lines README.md)" -le 150 ] || over "README.md: $(lines README.md) lines (at most 150)"
[ "$(lines BENCHMARKS.md)" -le 250 ] || over "BENCHMARKS.md: $(lines BENCHMARKS.md) lines (at most 250)"
while IFS= read -r page; do
  [ "$(lines "$page")" -le 400 ] || over "$page: $(lines "$page") lines (at most 400)"
done < <(git ls-files 'docs/*.md' 'docs/**/*.md')
patches=$(git ls-files '*.patch')
[ -z "$patches" ] || over "patch files tracked: $patches"
sittings=$(git grep -il sitting -- '*.rs' || true)
[ -z "$sittings" ] || over "comments cite a sitting: $sittings"
docs_bytes=$(git ls-files -z docs | xargs -0 cat | wc -c)
[ "$docs_bytes" -le $((2 * 1024 * 1024)) ] || over "docs/ tracks $docs_bytes bytes (at most 2 MiB)"
[ "$fail" = 0 ] && echo "README $(lines README.md) lines, BENCHMARKS $(lines BENCHMARKS.md) lines, docs/ $docs_bytes bytes: within the limits"
exit "$fail"
