#!/usr/bin/env python3
"""How often a perfect model meets the issue's criterion: the odds that the truth itself, compared
with its own synthetic data, has every reading's RMSE within 1.5x the injected noise.

    python3 tools/discovery/criterion_odds.py STUDY [STUDY ...] [--noise SPEC] [--draws N]
    python3 tools/discovery/criterion_odds.py --levels
    python3 tools/discovery/criterion_odds.py STUDY [STUDY ...] --test-bar R_J [R_J ...]
    python3 tools/discovery/criterion_odds.py STUDY [STUDY ...] --chi2-test R_J [R_J ...] [--alpha A]

`--chi2-test` gives the odds that such a fit fails the test's current check, the data's chi^2
over a study's rows at significance A (default 0.001), with the runs' scatters sampled as
`compare` estimates them (docs/discovery-proof.md, "The refit judged by the data's chi^2").
`--test-bar` gives instead the odds that a fit that found the truth misses the CI test's own
bar (1.5x the larger of the data's noise and the truth's own RMSE) with R_J runs per condition
in the judging compares.

STUDY is a hidden-effect study's OUT run with TRUTH=1 (tools/discovery/hidden_effect.sh): its
`data.csv` and its truth's compare `5-truth/compare.json`. NOISE is the injected noise the data
were made with (default: tools/discovery/setup.sh's, as tables.py).

Why. A measured value is the mean of R_d truth runs plus injected noise e (sd sigma); the truth's
compare is the mean of R_j other runs. For the truth, the residual of row i is therefore normal
with mean 0 and variance

    v_i = sigma_i^2 + s_i^2 / R_d + s_i^2 / R_j,

s_i the scatter of one run at that condition (the compare's `simulated_scatter`). Over a
reading's n conditions, RMSE^2 = sum r_i^2 / n. The criterion asks RMSE <= 1.5 x the RMS of
sigma_i. Even with infinitely many runs (v_i = sigma_i^2, all equal) that is
chi^2_n <= 2.25 n, which fails with a probability set by n alone: 6.1 % at 4 conditions,
2.7 % at 7. With four readings for each of three hidden effects, twelve chances. `--levels`
prints that bound against n; a STUDY gets the odds of its own design by Monte Carlo over the
v_i above, each reading independent of the others (their noise is; their run scatter is not
quite, since a steeper heap also holds more soil).

A fitted model's residuals are a little smaller than the truth's (its P free parameters absorb
P of the 4n dimensions of the noise), so its odds are a little better than these; they are the
odds of a fit that has found the truth.
"""
import argparse
import csv
import json
import math
import os
import random
import re
import sys

READINGS = ["heap_cone_angle_deg", "tray_mass_g", "funnel_flow_rate_g_s", "funnel_residue_g"]
BAR = 1.5


def default_noise():
    setup = open(os.path.join(os.path.dirname(__file__), "setup.sh")).read()
    return re.search(r"NOISE=\$\{NOISE:-([^}]*)\}", setup).group(1)


def parse_noise(spec):
    return dict(kv.split("=") for kv in spec.split(","))


def injected(spec, observable, value):
    """The injected noise's sd for one row: absolute, or a percentage of the measured value."""
    s = spec[observable]
    return float(s[:-1]) / 100 * abs(value) if s.endswith("%") else float(s)


def chi2_survival(x, k):
    """P(chi^2_k > x) for an integer k, in closed form (Abramowitz and Stegun 26.4.4-26.4.5)."""
    if x <= 0:
        return 1.0
    h = x / 2
    if k % 2 == 0:
        term, total = 1.0, 1.0
        for i in range(1, k // 2):
            term *= h / i
            total += term
        return math.exp(-h) * total
    total = math.erfc(math.sqrt(h))
    term = math.sqrt(h) / math.gamma(1.5)  # h^(1/2) / Gamma(3/2)
    for i in range(1, (k + 1) // 2):
        total += math.exp(-h) * term
        term *= h / (i + 0.5)
    return total


def perfect_pass(n):
    """The chance that one reading of a perfect model, with infinitely many runs, meets the bar
    at n conditions: P(chi^2_n <= BAR^2 n)."""
    return 1.0 - chi2_survival(BAR * BAR * n, n)


def reading_variances(study, spec):
    """Per reading: the injected sds and the truth's residual variances v_i, row by row."""
    with open(os.path.join(study, "data.csv")) as f:
        data = list(csv.DictReader(f))
    truth = json.load(open(os.path.join(study, "5-truth", "compare.json")))
    r_judge = truth["replicates"]
    scatter = {(r["observable"], json.dumps(r["conditions"], sort_keys=True)): r["simulated_scatter"]
               for r in truth["rows"]}
    out = {}
    for row in data:
        obs = row["observable"]
        cond = {"moisture_pct": float(row["moisture_pct"])}
        s = scatter[(obs, json.dumps(cond, sort_keys=True))]
        sigma = injected(spec, obs, float(row["value"]))
        v = sigma ** 2 + s ** 2 / float(row["replicates"]) + s ** 2 / r_judge
        out.setdefault(obs, []).append((sigma, v))
    return out


def pass_odds(rows, draws, rng):
    """Monte Carlo: the share of draws of the residuals r_i ~ N(0, v_i) whose RMSE is within
    BAR x the RMS injected noise."""
    n = len(rows)
    bar2 = BAR * BAR * sum(sigma * sigma for sigma, _ in rows) / n
    sds = [math.sqrt(v) for _, v in rows]
    ok = 0
    for _ in range(draws):
        if sum(rng.gauss(0.0, sd) ** 2 for sd in sds) / n <= bar2:
            ok += 1
    return ok / draws


def test_bar_rows(study):
    """Per reading, row by row: the data's uncertainty u_i (the injected noise and the scatter of
    the data's mean, as `synth` writes it) and one run's scatter s_i (the truth's compare)."""
    truth = json.load(open(os.path.join(study, "5-truth", "compare.json")))
    out = {}
    for r in truth["rows"]:
        out.setdefault(r["observable"], []).append((r["uncertainty"], r["simulated_scatter"]))
    return out


def test_bar_fails(rows, r_judge, draws, rng):
    """Monte Carlo: the share of draws in which a fit that found the truth misses the CI test's
    bar, RMSE_fit > BAR x max(noise, RMSE_truth). Row i's data error e_i ~ N(0, u_i^2) is shared
    by both compares; each compare's R_j-run mean adds its own N(0, s_i^2 / R_j)."""
    n = len(rows)
    noise2 = sum(u * u for u, _ in rows) / n
    bar2 = BAR * BAR
    fails = 0
    for _ in range(draws):
        fit2 = truth2 = 0.0
        for u, s in rows:
            e = rng.gauss(0.0, u)
            m = s / math.sqrt(r_judge)
            fit2 += (e + rng.gauss(0.0, m)) ** 2
            truth2 += (e + rng.gauss(0.0, m)) ** 2
        if fit2 / n > bar2 * max(noise2, truth2 / n):
            fails += 1
    return fails / draws


def chi2_rows(study, spec):
    """Per row of a study: the injected sd sigma_i, one run's scatter s_i (the truth's compare)
    and the replicates R_d behind the data's mean."""
    with open(os.path.join(study, "data.csv")) as f:
        data = {(r["observable"], float(r["moisture_pct"])): r for r in csv.DictReader(f)}
    truth = json.load(open(os.path.join(study, "5-truth", "compare.json")))
    out = []
    for r in truth["rows"]:
        d = data[(r["observable"], float(r["conditions"]["moisture_pct"]))]
        out.append((injected(spec, r["observable"], float(d["value"])), r["simulated_scatter"],
                    int(d["replicates"])))
    return out


def chi2_test_fails(rows, r_judge, alpha, draws, rng):
    """Monte Carlo: the share of draws in which a fit that found the truth fails the CI test's
    consistency check, P(chi^2_n > X) < alpha with X = sum z_i^2 over the study's n rows, as
    `tilth compare` computes it: z_i = (mean of R_j runs - value) / sqrt(u_i^2 + s'_i^2 / R_j).
    The value is the mean of R_d truth runs plus N(0, sigma_i^2); its uncertainty u_i^2 =
    sigma_i^2 + s''_i^2 / R_d. Both scatters s'_i, s''_i are sample sds of their runs
    (s_i^2 chi^2_{R-1} / (R - 1)), which gives X a heavier tail than chi^2_n."""
    n = len(rows)
    fails = 0
    for _ in range(draws):
        x = 0.0
        for sigma, s, r_data in rows:
            e = rng.gauss(0.0, sigma) + rng.gauss(0.0, s / math.sqrt(r_data))
            u2 = sigma * sigma + s * s * rng.gammavariate((r_data - 1) / 2, 2) / (r_data - 1) / r_data
            m = rng.gauss(0.0, s / math.sqrt(r_judge))
            sj2 = s * s * rng.gammavariate((r_judge - 1) / 2, 2) / (r_judge - 1)
            x += (m - e) ** 2 / (u2 + sj2 / r_judge)
        if chi2_survival(x, n) < alpha:
            fails += 1
    return fails / draws


def chi2_test_table(studies, spec, r_judges, alpha, draws, seed):
    rng = random.Random(seed)
    print(f"| R_j | " + " | ".join(os.path.basename(os.path.normpath(s)) for s in studies)
          + " | any study |")
    print("|---" * (len(studies) + 2) + "|")
    for r_judge in r_judges:
        fails = [chi2_test_fails(chi2_rows(s, spec), r_judge, alpha, draws, rng) for s in studies]
        print(f"| {r_judge} | " + " | ".join(f"{f:.4f}" for f in fails)
              + f" | {1.0 - math.prod(1.0 - f for f in fails):.4f} |")
    print(f"\n(alpha = {alpha}; known scatters instead of sampled ones: chi^2_n's own alpha)")


def test_bar_table(studies, r_judges, draws, seed):
    rng = random.Random(seed)
    print("| study | R_j | " + " | ".join(READINGS) + " | any of the four |")
    print("|---" * (len(READINGS) + 3) + "|")
    for r_judge in r_judges:
        every = 1.0
        for study in studies:
            per = test_bar_rows(study)
            fails = [test_bar_fails(per[o], r_judge, draws, rng) for o in READINGS]
            passes = math.prod(1.0 - f for f in fails)
            every *= passes
            print(f"| {os.path.basename(os.path.normpath(study))} | {r_judge} | "
                  + " | ".join(f"{f:.4f}" for f in fails) + f" | {1.0 - passes:.3f} |")
        print(f"| all studies, R_j = {r_judge} | | | | | | {1.0 - every:.3f} |")


def study_table(studies, spec, draws, seed):
    rng = random.Random(seed)
    print("| study | " + " | ".join(READINGS) + " | all four |")
    print("|---" * (len(READINGS) + 2) + "|")
    every = 1.0
    for study in studies:
        per = reading_variances(study, spec)
        odds = [pass_odds(per[o], draws, rng) if o in per else float("nan") for o in READINGS]
        both = math.prod(p for p in odds if not math.isnan(p))
        every *= both
        n = len(next(iter(per.values())))
        print(f"| {os.path.basename(os.path.normpath(study))} ({n} levels) | "
              + " | ".join(f"{p:.3f}" for p in odds) + f" | {both:.3f} |")
    print(f"\nall studies together: {every:.3f} (readings taken as independent)")


def levels_table():
    print("| conditions n | one reading | twelve readings |")
    print("|---|---|---|")
    for n in [4, 7, 10, 12, 16, 20, 28]:
        p = perfect_pass(n)
        print(f"| {n} | {p:.4f} | {p ** 12:.3f} |")


def main(argv):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("studies", nargs="*")
    ap.add_argument("--noise", default=None)
    ap.add_argument("--draws", type=int, default=20000)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--levels", action="store_true")
    ap.add_argument("--test-bar", type=int, nargs="+", metavar="R_J",
                    help="the odds that a fit that found the truth misses the CI test's bar, "
                    "with R_J runs per condition in the judging compares")
    ap.add_argument("--chi2-test", type=int, nargs="+", metavar="R_J",
                    help="the odds that a fit that found the truth fails the CI test's chi^2 "
                    "consistency check at --alpha, with R_J runs per condition in its compare")
    ap.add_argument("--alpha", type=float, default=0.001)
    a = ap.parse_args(argv)
    if a.levels:
        levels_table()
    if a.studies and a.chi2_test:
        chi2_test_table(a.studies, parse_noise(a.noise or default_noise()), a.chi2_test, a.alpha,
                        a.draws, a.seed)
    elif a.studies and a.test_bar:
        test_bar_table(a.studies, a.test_bar, a.draws, a.seed)
    elif a.studies:
        study_table(a.studies, parse_noise(a.noise or default_noise()), a.draws, a.seed)
    if not a.levels and not a.studies:
        ap.error("give a STUDY or --levels")


if __name__ == "__main__":
    main(sys.argv[1:])
