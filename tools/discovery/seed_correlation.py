#!/usr/bin/env python3
"""How alike one replicate's runs are across the conditions of a compare.

    python3 tools/discovery/seed_correlation.py DIR/compare.json

For each observable with at least two conditions and three replicates: every run's deviation
from its condition's mean, over that condition's scatter (z), and the correlation of z
between two conditions over the replicates, sum_k z_a,k z_b,k / (R - 1), averaged over every
pair of conditions. Near 0: the conditions' runs are independent draws, and a row's
simulation error averages out across rows. Near 1: replicate k shifts every condition
alike, so R runs per condition carry one common error that no number of conditions averages
out (docs/discovery-proof.md, "The stop rule and the seeds").
"""

from __future__ import annotations

import itertools
import json
import statistics
import sys


def correlations(compare: dict) -> dict[str, tuple[float, int]]:
    """Per observable: the mean cross-condition correlation and the number of pairs."""
    out = {}
    observables = sorted({r["observable"] for r in compare["rows"]})
    for ob in observables:
        runs = [r["simulated"] for r in compare["rows"] if r["observable"] == ob]
        replicates = min(len(x) for x in runs)
        if len(runs) < 2 or replicates < 3:
            continue
        z = []
        for x in runs:
            x = x[:replicates]
            mean, sd = statistics.mean(x), statistics.stdev(x)
            # A reading that does not scatter (every run the same) has no deviations to share.
            z.append([(v - mean) / sd if sd > 0 else 0.0 for v in x])
        pairs = [
            sum(a[k] * b[k] for k in range(replicates)) / (replicates - 1)
            for a, b in itertools.combinations(z, 2)
        ]
        out[ob] = (statistics.mean(pairs), len(pairs))
    return out


def main(argv: list[str]) -> int:
    if len(argv) != 2:
        print(__doc__.strip().splitlines()[2], file=sys.stderr)
        return 2
    with open(argv[1]) as f:
        compare = json.load(f)
    print("| observable | mean correlation between conditions | pairs |")
    print("|---|---|---|")
    for ob, (c, n) in correlations(compare).items():
        print(f"| {ob} | {c:+.2f} | {n} |")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
