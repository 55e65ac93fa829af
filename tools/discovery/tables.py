#!/usr/bin/env python3
"""The discovery proof's tables (docs/discovery-proof.md, "The proof") from its output directory.

    python3 tools/discovery/tables.py DIR [NOISE]
    python3 tools/discovery/tables.py --one OUT [NOISE]

DIR holds `hidden-<effect>/` (tools/discovery/hidden_effect.sh) and `null/` (null_study.sh),
as the proof's test leaves them in target/tmp/discovery-proof; `--one` reads one
hidden-effect study's OUT. NOISE is the injected noise the data were made with (default:
tools/discovery/setup.sh's). The error after the fit is given against the data's noise (the
RMS of their `uncertainty`: the injected noise and the scatter of the truth's mean, which
the proof's test judges) and against the injected noise alone. A study run with TRUTH=1 also
holds the truth's own compare with its data (`5-truth/`): its error is the one a perfect fit
would leave on that draw of the noise, and a table sets the fitted model's beside it. Prints
Markdown.
"""
import glob
import json
import math
import os
import re
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from criterion_odds import chi2_survival  # noqa: E402

READINGS = ["heap_cone_angle_deg", "tray_mass_g", "funnel_flow_rate_g_s", "funnel_residue_g"]
HEADS = dict(zip(READINGS, ["cone angle (deg)", "tray mass (g)", "flow rate (g/s)", "residue (g)"]))


def default_noise():
    setup = open(os.path.join(os.path.dirname(__file__), "setup.sh")).read()
    return re.search(r"NOISE=\$\{NOISE:-([^}]*)\}", setup).group(1)


def injected(spec, observable, value):
    s = spec[observable]
    return float(s[:-1]) / 100 * abs(value) if s.endswith("%") else float(s)


def load(path):
    with open(path) as f:
        return json.load(f)


def hidden(study):
    """The effect hidden in a study's data and its strength, from the data's `source`
    ("synth: truth M with NAME=S; ...")."""
    with open(f"{study}/data.csv") as f:
        return re.search(r"with ([a-z_]+)=([0-9.e-]+)", f.read()).groups()


def rms(xs):
    return math.sqrt(sum(x * x for x in xs) / len(xs))


def hidden_tables(dirs, spec):
    print("| hidden (strength) | ranked first | statistic | p (Holm) | estimated strength "
          "| second (p) | fitted strength | its standard error | z | chi^2 / dof after |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for d in dirs:
        effect, strength = hidden(d)
        c = load(f"{d}/2-diagnose/diagnosis.json")["candidates"]
        fit = load(f"{d}/3-fit/fit.json")
        k = next(i for i, p in enumerate(fit["parameters"]) if p["label"].startswith("candidate."))
        # The fit's standard error (null: not determined; absent before 2026-11-30) and how
        # many of them the fitted strength is from the hidden one, when it is that candidate.
        se = (fit.get("standard_error") or [None] * (k + 1))[k]
        z = (fit["estimate"][k] - float(strength)) / se if se and fit["parameters"][k]["label"] == f"candidate.{effect}" else None
        print(f"| {effect} ({strength}) | {c[0]['name']} | {c[0]['statistic']:.1f} | {c[0]['p_value']:.2g} "
              f"| {c[0]['strength']:.4f} | {c[1]['name']} ({c[1]['p_value']:.2g}) "
              f"| {fit['estimate'][k]:.4f} | {'-' if se is None else f'{se:.4f}'} "
              f"| {'-' if z is None else f'{z:.2f}'} | {fit['chi2']:.1f} / {fit['dof']} |")
    print()
    print("RMSE before -> after the fit (after / the data's noise, after / the injected noise):")
    print()
    present = {r["observable"] for d in dirs for r in load(f"{d}/1-compare/compare.json")["rows"]}
    readings = [o for o in READINGS if o in present] + sorted(present - set(READINGS))
    print("| hidden | " + " | ".join(HEADS.get(o, o) for o in readings) + " |")
    print("|---" * (len(readings) + 1) + "|")
    worst = [0.0, 0.0]
    truth_rows = []  # studies run with TRUTH=1: the fit's and the truth's error / injected noise
    for d in dirs:
        first = load(f"{d}/1-compare/compare.json")
        rows, before = first["rows"], first["observables"]
        after = load(f"{d}/4-compare/compare.json")["observables"]
        truth_file = f"{d}/5-truth/compare.json"
        truth = load(truth_file)["observables"] if os.path.exists(truth_file) else None
        cells, truth_cells = [], []
        for o in readings:
            mine = [r for r in rows if r["observable"] == o]
            noise = rms([injected(spec, o, r["value"]) for r in mine])
            ratios = [after[o]["rmse"] / rms([r["uncertainty"] for r in mine]), after[o]["rmse"] / noise]
            worst = [max(w, x) for w, x in zip(worst, ratios)]
            cells.append(f"{before[o]['rmse']:.3g} -> {after[o]['rmse']:.3g} ({ratios[0]:.2f}, {ratios[1]:.2f})")
            if truth is not None:
                truth_cells.append(f"{ratios[1]:.2f} (truth {truth[o]['rmse'] / noise:.2f})")
        print(f"| {hidden(d)[0]} | " + " | ".join(cells) + " |")
        if truth is not None:
            truth_rows.append(f"| {hidden(d)[0]} | " + " | ".join(truth_cells) + " |")
    print()
    print(f"largest RMSE after: {worst[0]:.2f}x the data's noise, {worst[1]:.2f}x the injected noise")
    if truth_rows:
        print()
        print("RMSE / injected noise, the fitted model against the truth itself (the same data, "
              "as many runs per condition):")
        print()
        print("| hidden | " + " | ".join(HEADS.get(o, o) for o in readings) + " |")
        print("|---" * (len(readings) + 1) + "|")
        print("\n".join(truth_rows))
    chi2_table(dirs)


def chi2_of(compare):
    """A compare's chi^2 over all its rows (its readings' sum z_i^2), the rows, and the p-value:
    what the proof's test judges a fit by (runner/tests/runner/discovery_proof.rs). None for a
    compare without verdicts."""
    if "verdicts" not in compare:
        return None
    x = sum(v["chi2"][0] for v in compare["verdicts"])
    n = sum(v["n"] for v in compare["verdicts"])
    return x, n, chi2_survival(x, n)


def chi2_table(dirs):
    print()
    print("The data's chi^2 over each study's rows (the test asks p >= 0.001 after the fit, and "
          "a lower chi^2 than before it):")
    print()
    print("| hidden | before the fit | after | the truth's own compare |")
    print("|---|---|---|---|")
    for d in dirs:
        cells = []
        for name in ["1-compare", "4-compare", "5-truth"]:
            path = f"{d}/{name}/compare.json"
            # "-": no such compare (a study run without TRUTH=1), or one written before
            # `compare` gave its verdicts.
            c = chi2_of(load(path)) if os.path.exists(path) else None
            cells.append("-" if c is None else f"{c[0]:.1f} on {c[1]} (p = {c[2]:.2g})")
        print(f"| {hidden(d)[0]} | " + " | ".join(cells) + " |")


def null_table(root):
    seeds = sorted(glob.glob(os.path.join(root, "null", "seed-*")), key=lambda p: int(p.rsplit("-", 1)[1]))
    if not seeds:
        return
    print()
    print("| seed | first candidate | statistic | p (Holm) |")
    print("|---|---|---|---|")
    flagged, smallest = 0, 1.0
    for s in seeds:
        c = load(f"{s}/diagnose/diagnosis.json")["candidates"]
        flagged += any(x["significant"] for x in c)
        smallest = min(smallest, c[0]["p_value"])
        print(f"| {s.rsplit('-', 1)[1]} | {c[0]['name']} | {c[0]['statistic']:.2f} | {c[0]['p_value']:.3g} |")
    print()
    print(f"seeds with a significant candidate: {flagged} of {len(seeds)}; smallest corrected p: {smallest:.2g}")


def main():
    args = sys.argv[1:]
    one = args[:1] == ["--one"]
    args = args[1:] if one else args
    if len(args) not in (1, 2):
        sys.exit(__doc__)
    spec = dict(p.split("=") for p in (args[1] if len(args) == 2 else default_noise()).split(","))
    if one:
        hidden_tables([args[0]], spec)
    else:
        hidden_tables(sorted(glob.glob(os.path.join(args[0], "hidden-*"))), spec)
        null_table(args[0])


if __name__ == "__main__":
    main()
