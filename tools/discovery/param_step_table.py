#!/usr/bin/env python3
"""The table of docs/discovery-proof.md, "The free parameters' step in `diagnose`": for each
diagnosis sub-directory of a finished discovery proof (one per free-parameter step), how often
each hidden effect is ranked first and significant, how many null seeds have a significant
candidate, how often the free parameter is `measurable`, and the mean recalibration shift and
estimated strength per effect.

    tools/discovery/param_step_table.py PROOF SUB=LABEL...
    tools/discovery/param_step_table.py target/tmp/discovery-proof \\
        diagnose-02="2 %" 2-diagnose="5 % (default)" diagnose-25="25 %"

The proof's own diagnoses are `2-diagnose` in the draws and `diagnose` in the null seeds;
SUB `2-diagnose` reads both. Hidden effects and strengths: the proof's
(runner/tests/runner/discovery_proof.rs).
"""

from __future__ import annotations

import json
import statistics
import sys
from pathlib import Path

HIDDEN = {"fines": 0.15, "wall_adhesion": 0.02, "plastic_adhesion": 0.04}


def diagnosis(case: Path, sub: str) -> dict:
    d = case / sub
    if sub == "2-diagnose" and not d.exists():
        d = case / "diagnose"
    return json.loads((d / "diagnosis.json").read_text())


def row(proof: Path, sub: str) -> dict:
    """One step's numbers: per effect, (hits, draws, mean shift, mean strength); the null
    seeds' false alarms; the free parameter measurable (count, diagnoses)."""
    effects, measurable, total = {}, 0, 0
    for effect in HIDDEN:
        hits, shifts, strengths = 0, [], []
        draws = sorted((proof / f"rate-{effect}").glob("seed*"))
        for case in draws:
            d = diagnosis(case, sub)
            top = d["candidates"][0]
            hits += top["name"] == effect and top["significant"]
            (recal,) = d["recalibration"]
            measurable += recal["measurable"]
            total += 1
            shifts.append(recal["shift"])
            strengths.append(next(c for c in d["candidates"] if c["name"] == effect)["strength"])
        effects[effect] = (hits, len(draws), statistics.mean(shifts), statistics.mean(strengths))
    nulls = sorted((proof / "null").glob("seed-*"))
    alarms = sum(any(c["significant"] for c in diagnosis(s, sub)["candidates"]) for s in nulls)
    return {"effects": effects, "alarms": (alarms, len(nulls)), "measurable": (measurable, total)}


def table(proof: Path, subs: list[tuple[str, str]]) -> str:
    names = " / ".join(HIDDEN)
    truths = " / ".join(f"{e} {s}" for e, s in HIDDEN.items())
    lines = [
        f"| step | ranked first and significant ({names}) | null seeds with a significant "
        f"candidate | free parameter measurable | mean recalibration shift ({names}) | "
        f"mean strength ({truths}) |",
        "|---|---|---|---|---|---|",
    ]
    for sub, label in subs:
        r = row(proof, sub)
        e = r["effects"].values()
        lines.append(
            f"| {label} | {' / '.join(f'{h}/{n}' for h, n, _, _ in e)} | "
            f"{r['alarms'][0]}/{r['alarms'][1]} | {r['measurable'][0]}/{r['measurable'][1]} | "
            f"{' / '.join(f'{s:+.3f}' for _, _, s, _ in e)} | "
            f"{' / '.join(f'{v:.4f}' for _, _, _, v in e)} |"
        )
    return "\n".join(lines)


if __name__ == "__main__":
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    pairs = [a.split("=", 1) if "=" in a else [a, a] for a in sys.argv[2:]]
    print(table(Path(sys.argv[1]), [(s, l) for s, l in pairs]))
