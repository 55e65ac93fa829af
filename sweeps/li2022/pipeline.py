#!/usr/bin/env python3
"""The reference study (Li et al. 2022) as one pipeline, with tilth's own simulations.

    sweeps/li2022/pipeline.py OUT [--cores N] [--replicates N] [--bonds MODEL]
                              [--bond-replicates N] [--repose-model MODEL]
                              [--repose-param PAIR.KEY=LO:HI]
                              [--surface-seeds N] [--check-seeds N]
                              [--stages STAGE,...] [--tilth PATH]

Plackett-Burman screening (pb.toml, table 6) -> its ANOVA beside the study's (table 7) ->
the steepest-ascent path (steepest_ascent.toml, table 8) -> the next design's ranges from the
path's best run (`tilth rsm next`, as the study chose table 9's levels) -> Box-Behnken
(bbd.toml with those ranges, table 9) -> the study's error-rate fits per moisture (table 10,
equations 10-13) and the angle's own fit solved for each moisture's measured angle (the
ridge) -> one setting per moisture (restitution at the study's 0.45, the ridge point nearest
the design centre) -> validation runs of the funnel test at each moisture with several seeds
(`tilth compare`) against table 1, beside the study's own validation (table 11) -> the angle
calibrated again on a quieter heap (stage `repose-calibration`): `tilth calibrate`
per moisture on a funnel heap that scatters by 1-3 degrees between seeds instead of 5-7
(QUIET_FUNNEL), from a model with twisting resistance (REPOSE_MODEL), with seeds repeated at
every setting, then fresh seeds through `tilth compare` as the verdict -> the moistures that
verdict missed, refined and validated on fresh seeds again (stage `repose-refinement`) -> the bonded specimens: the direct shear box and the unconfined compression test at every
condition of tables 12 and 13, with the bond strengths of a calibrated model file (`--bonds`,
by default models/li2022-per-test-bonds.toml, whose calibration that document
describes), against the measurements and beside the study's own simulated values.

Everything is written under OUT: each sweep's runs and results.csv, every command's output,
the calibrated model (OUT/model.toml) and OUT/report.md, which puts each of the study's
tables beside tilth's numbers. Each step is resumable (sweeps skip finished runs), so an
interrupted pipeline picks up where it stopped when run again with the same OUT.

Only the Python standard library is used; `tilth` must be on PATH (or --tilth).
"""

import argparse
import csv
import json
import math
import re
import shutil
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
REPO = HERE.parent.parent
DATA = HERE / "data"
MOISTURES = [3, 6, 9, 12]
FACTORS7 = ["x1", "x2", "x3", "x4", "x5", "x6", "x7"]
PATH_FACTORS = ["x4", "x6", "x7"]
STUDY_RESTITUTION = 0.45  # table 11: the study fixed x4 at 0.45 for every moisture
STAGES = ["repose", "repose-calibration", "repose-refinement", "bonds"]
# The funnel heap tilth calibrates the angle on (docs/li2022-repose-calibration.md): the
# study's tester scaled to the coarse preset's 4 mm grains, so that the heap is as many grains
# across as the study's 2 mm heap was, poured at the study's mass flow. `tilth calibrate` and
# `tilth compare` put these keys into every funnel run (`--set repose.KEY=VALUE`).
QUIET_FUNNEL = [
    ("tray_diameter", 0.1236),  # m: twice the study's 61.8 mm tray, for grains twice as big
    ("drop_height", 0.12),      # m: the outlet twice as high above the tray
    ("mass_g", 300),            # as much soil as the tray holds at 45 degrees, and some overflow
    ("rate", 2500),             # grains/s: 116 g/s, the study's 20,000 grains/s of 2 mm
    ("photographs", 8),         # silhouettes averaged per heap
]
# The repose stages' starting model: the quiet heap's model with Marshall twisting resistance
# at the sliding friction (no new free parameter). Calibrated and refined from it, the angle is
# within 2 % of table 1 at all four moistures; from the model without twisting
# (models/li2022-repose.toml, range 0.1:0.6) the 12 % heap stays near 43
# degrees (docs/li2022-repose-calibration.md).
REPOSE_MODEL = REPO / "models" / "li2022-repose-twisting.toml"
# The free parameter, one value per moisture (the surface energy is fixed on a line in
# moisture by the starting model: one angle per moisture cannot separate the two). With
# twisting resistance the dry heap needs less rolling friction, hence the range's low end.
REPOSE_PARAM = "soil-soil.rolling_friction=0.05:0.6"
# The validation's first seed: `tilth calibrate` runs its surface from seed 1 and its direct
# checks from 1001, so the validation from 2001 on shares no run with the calibration.
VALIDATION_FIRST_SEED = 2001
REPOSE_TOLERANCE = 2.0  # %: issue 5's target; the study's worst validation error was 4.72 %
# The refinement (stage `repose-refinement`) of the moistures the validation missed: its seeds
# come after every seed the calibration and the validation used.
REFINEMENT_FIRST_SEED = 3001
# Where the calibrated rolling friction sits at an end of its range, it cannot move the angle
# further: the surface energy at that moisture is freed instead, from the starting model's
# line (0.1 J/m^2 at 12 %) to 2.5 times it, with the rolling friction back at the middle of
# its range (where the 12 % heap scattered by 1.2 degrees between seeds, against 2-2.8 at 0.6).
REFINE_COHESION = "soil-soil.surface_energy=0.1:0.25"
# The study's error bands (its worst errors, section "What the study calibrated" of
# docs/experiments.md): peak shear force 3.71-6.53 %, UCS 0.6-8.07 %.
BOND_TABLES = [
    # (test, observable, study table, its CSV, measured column, simulated column, band %)
    ("direct_shear", "peak_shear_force_n", 12, "table12_shear_peak_force.csv",
     "peak_shear_force_measured_n", "peak_shear_force_simulated_n", 6.53),
    ("ucs", "ucs_kpa", 13, "table13_ucs_peak.csv", "measured_value", "simulated_value", 8.07),
]


def read_csv(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def at_coarse_preset():
    """Whether the designs run at the coarse preset (pb.toml's `[fixed]`): every stage follows."""
    return '"coarse" = true' in (HERE / "pb.toml").read_text()


def measured_angles():
    return {int(r["moisture_pct"]): float(r["repose_angle_deg"])
            for r in read_csv(DATA / "table01_friction_repose.csv")}


class Pipeline:
    def __init__(self, args):
        self.out = Path(args.out).resolve()
        self.out.mkdir(parents=True, exist_ok=True)
        self.tilth = args.tilth
        self.cores = str(args.cores)
        self.replicates = args.replicates
        # The repose stages' free parameter and range: the calibration's, and the
        # refinement's (which refines that calibration's settings within the same range).
        self.repose_param = args.repose_param
        self.report = []

    def run(self, *argv, capture=None):
        """Runs tilth; with `capture`, its stdout also goes to OUT/capture."""
        cmd = [self.tilth, *map(str, argv)]
        print("$ " + " ".join(cmd), file=sys.stderr, flush=True)
        done = subprocess.run(cmd, stdout=subprocess.PIPE, text=True)
        if capture:
            (self.out / capture).write_text(done.stdout)
        if done.returncode != 0:
            sys.exit(f"pipeline: `{' '.join(cmd)}` failed (exit {done.returncode})")
        return done.stdout

    def sweep(self, sweep_file, name):
        """Runs a sweep; runs that failed stay failed (the fits leave them out, naming them)."""
        cmd = [self.tilth, "sweep", "run", str(sweep_file), "--out", str(self.out / name),
               "--cores", self.cores, "--quiet"]
        print("$ " + " ".join(cmd), file=sys.stderr, flush=True)
        code = subprocess.run(cmd).returncode
        results = self.out / name / "results.csv"
        if not results.exists():
            sys.exit(f"pipeline: {sweep_file} wrote no results (exit {code})")
        return read_csv(results)

    def h(self, text):
        self.report.append(f"\n## {text}\n")

    def p(self, text=""):
        self.report.append(text)

    def block(self, text):
        self.report.append("```\n" + text.rstrip() + "\n```")

    # 1. Plackett-Burman -----------------------------------------------------------------
    def screening(self):
        rows = self.sweep(HERE / "pb.toml", "pb")
        study = read_csv(DATA / "table06_pb_runs.csv")
        self.h("Table 6: Plackett-Burman screening, the study's angle and tilth's")
        self.p("| run | x1..x7 (coded) | study, deg | tilth, deg | tilth status |")
        self.p("|---|---|---|---|---|")
        for s, t in zip(study, rows):
            coded = " ".join(sign(s[f]) for f in FACTORS7)
            self.p(f"| {s['run']} | {coded} | {float(s['repose_angle_deg']):.2f} | "
                   f"{fmt(t.get('repose_angle_deg'))} | {t['status']} |")
        self.p()
        text = self.run("rsm", "fit", self.out / "pb" / "results.csv",
                        "--response", "repose_angle_deg", "--factors", ",".join(FACTORS7),
                        "--centre-curvature", "--plot", self.out / "pb",
                        capture="pb-anova.txt")
        study_text = self.run("rsm", "fit", DATA / "table06_pb_runs.csv",
                              "--response", "repose_angle_deg", "--factors", ",".join(FACTORS7),
                              "--centre-curvature", "--reported",
                              DATA / "table07_pb_anova_reported.csv",
                              capture="pb-anova-study.txt")
        self.h("Table 7: the screening's ANOVA")
        self.p("The study's (from its table 6, beside its printed table 7):")
        self.block(study_text)
        self.p("tilth's, from its own runs (Pareto and main-effect charts in `pb/`):")
        self.block(text)

    # 2. Steepest ascent -----------------------------------------------------------------
    def steepest_ascent(self):
        rows = self.sweep(HERE / "steepest_ascent.toml", "steepest_ascent")
        study = read_csv(DATA / "table08_steepest_ascent.csv")
        targets = measured_angles()
        self.h("Table 8: steepest ascent along x4, x6, x7")
        self.p("| step | x4 | x6 | x7 | study, deg | tilth, deg |")
        self.p("|---|---|---|---|---|---|")
        for s, t in zip(study, rows):
            self.p(f"| {s['run']} | {s['x4']} | {s['x6']} | {s['x7']} | "
                   f"{float(s['repose_angle_deg']):.2f} | {fmt(t.get('repose_angle_deg'))} |")
        self.p()
        target = ",".join(f"{targets[m]}" for m in MOISTURES)
        nxt = json.loads(self.run("rsm", "next", self.out / "steepest_ascent" / "results.csv",
                                  "--response", "repose_angle_deg",
                                  "--factors", ",".join(PATH_FACTORS), "--target", target,
                                  "--neighbours", "2", "--json", capture="next.json"))
        study_next = json.loads(self.run("rsm", "next", DATA / "table08_steepest_ascent.csv",
                                         "--response", "repose_angle_deg",
                                         "--factors", ",".join(PATH_FACTORS),
                                         "--target", target, "--neighbours", "2", "--json"))
        self.p(f"tilth: {nxt['statement']}.")
        self.p()
        self.p(f"The study's path, by the same rule: {study_next['statement']} "
               "(table 9's levels).")
        return nxt

    # 3. Box-Behnken ---------------------------------------------------------------------
    def box_behnken(self, nxt):
        text = (HERE / "bbd.toml").read_text()
        text = text.replace('scene = "../experiments/repose.toml"',
                            f'scene = "{(HERE.parent / "experiments" / "repose.toml").as_posix()}"')
        blocks = text.split("[[factors]]")
        for f, lo, hi in zip(nxt["factors"], nxt["low"], nxt["high"]):
            mine = [i for i, b in enumerate(blocks) if re.search(rf'^name = "{f}"$', b, re.M)]
            if len(mine) != 1:
                sys.exit(f"pipeline: bbd.toml has no factor `{f}`")
            b = re.sub(r"^low = .*$", f"low = {lo:.6g}", blocks[mine[0]], count=1, flags=re.M)
            blocks[mine[0]] = re.sub(r"^high = .*$", f"high = {hi:.6g}", b, count=1, flags=re.M)
        text = "[[factors]]".join(blocks)
        bbd = self.out / "bbd.toml"
        bbd.write_text("# Written by pipeline.py: bbd.toml with the ranges `tilth rsm next` chose.\n"
                       + text)
        rows = self.sweep(bbd, "bbd")
        targets = measured_angles()
        # The study's response per moisture: the relative error of the simulated angle.
        table = self.out / "bbd" / "errors.csv"
        with open(table, "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(PATH_FACTORS + ["repose_angle_deg"] + [f"err_{m}pct" for m in MOISTURES])
            for r in rows:
                a = r.get("repose_angle_deg") or ""
                errs = [f"{abs(float(a) - targets[m]) / targets[m]:.6f}" if a else ""
                        for m in MOISTURES]
                w.writerow([r[f] for f in PATH_FACTORS] + [a] + errs)
        study = read_csv(DATA / "table09_bbd_runs.csv")
        self.h("Table 9: Box-Behnken runs")
        self.p("| run | x4, x6, x7 (coded) | study, deg | tilth, deg | tilth status |")
        self.p("|---|---|---|---|---|")
        for i, t in enumerate(rows):
            s = study[i] if i < len(study) else None
            coded = " ".join(sign(s[f + "_coded"]) for f in PATH_FACTORS) if s else "0 0 0"
            angle = f"{float(s['repose_angle_deg']):.2f}" if s else "(not printed)"
            self.p(f"| {i + 1} | {coded} | {angle} | {fmt(t.get('repose_angle_deg'))} | {t['status']} |")
        self.p()
        reported = read_csv(DATA / "table10_bbd_anova_reported.csv")
        r2_study = {m: next(r[f"p_{m}pct"] for r in reported if r["source"] == "r_squared")
                    for m in MOISTURES}
        self.h("Table 10, equations (10)-(13): quadratic fits of the error rate per moisture")
        summary = ["| moisture | study R^2 | tilth R^2 | tilth adj. R^2 | tilth pred. R^2 |",
                   "|---|---|---|---|---|"]
        texts = []
        for m in MOISTURES:
            out = self.run("rsm", "fit", table, "--response", f"err_{m}pct",
                           "--factors", ",".join(PATH_FACTORS), "--model", "quadratic",
                           "--json", capture=f"bbd-err-{m}pct.json")
            fit = json.loads(out)
            summary.append(f"| {m} % | {r2_study[m]} | {fit['r2']:.4f} | {fit['adj_r2']:.4f} | "
                           f"{fmt(fit.get('pred_r2'))} |")
            texts.append((m, self.run("rsm", "fit", table, "--response", f"err_{m}pct",
                                      "--factors", ",".join(PATH_FACTORS), "--model", "quadratic",
                                      capture=f"bbd-err-{m}pct.txt")))
        self.p("\n".join(summary))
        self.p()
        for m, t in texts:
            self.p(f"tilth, {m} % moisture:")
            self.block(t)
        return nxt

    # 4. Solve per moisture --------------------------------------------------------------
    def solve(self, nxt):
        targets = measured_angles()
        target = ",".join(f"{m}%={targets[m]}" for m in MOISTURES)
        table = self.out / "bbd" / "results.csv"
        common = ["rsm", "solve", table, "--response", "repose_angle_deg",
                  "--factors", ",".join(PATH_FACTORS), "--model", "quadratic",
                  "--fix", f"x4={STUDY_RESTITUTION}", "--target", target]
        text = self.run(*common, "--plot", self.out / "solve", capture="solve.txt")
        solved = json.loads(self.run(*common, "--json", capture="solve.json"))
        centre = [(lo + hi) / 2 for lo, hi in zip(nxt["low"], nxt["high"])]
        half = [(hi - lo) / 2 for lo, hi in zip(nxt["low"], nxt["high"])]
        chosen = {}
        for m, s in zip(MOISTURES, solved["solutions"]):
            candidates = s["settings"] or ([s["closest"]] if s.get("closest") else [])
            if not candidates:
                sys.exit(f"pipeline: no setting found for {m} % moisture")
            best = min(candidates, key=lambda c: sum(((v - c0) / h) ** 2 for v, c0, h
                                                       in zip(c["values"], centre, half)))
            chosen[m] = (best["values"], bool(s["settings"]), s["statement"])
        study = {int(r["moisture_pct"]): r for r in read_csv(DATA / "table11_calibrated_contact.csv")}
        self.h("Table 11: the calibrated contact parameters")
        self.p("The angle's own quadratic fit, solved for each moisture's measured angle with x4 "
               f"fixed at the study's {STUDY_RESTITUTION}; where one angle leaves a ridge of "
               "settings, the pipeline takes the point nearest the design centre (coded units) "
               "and says so. `tilth rsm solve` in full:")
        self.block(text)
        self.p("| moisture | study x6, x7 | tilth x6, x7 | tilth's choice |")
        self.p("|---|---|---|---|")
        for m in MOISTURES:
            v, on_ridge, _ = chosen[m]
            self.p(f"| {m} % | {study[m]['soil_soil_rolling_friction']}, "
                   f"{study[m]['jkr_surface_energy_j_per_m2']} | {v[1]:.4f}, {v[2]:.4f} | "
                   f"{'ridge point nearest the centre' if on_ridge else 'no exact solution: the closest prediction'} |")
        self.p()
        return chosen

    # 5. Validation ----------------------------------------------------------------------
    def validate(self, chosen):
        model = (REPO / "models" / "li2022.toml").read_text()
        xs = ", ".join(str(m) for m in MOISTURES)

        def table(i):
            return ("{ interpolate = \"moisture_pct\", x = [" + xs + "], y = ["
                    + ", ".join(f"{chosen[m][0][i]:.6g}" for m in MOISTURES) + "] }")

        model = set_pair_key(model, "soil-soil", "restitution", f"{STUDY_RESTITUTION}")
        model = set_pair_key(model, "soil-soil", "rolling_friction", table(1))
        model = set_pair_key(model, "soil-soil", "surface_energy", table(2))
        # The surfaces were fitted with the screening's other factors at its centre.
        model = set_pair_key(model, "soil-soil", "friction", "0.8")
        model = set_pair_key(model, "soil-steel", "restitution", "0.35")
        model = set_pair_key(model, "soil-steel", "friction", "0.85")
        model = set_pair_key(model, "soil-steel", "rolling_friction", "0.225")
        path = self.out / "model.toml"
        model = ("# Written by sweeps/li2022/pipeline.py: models/li2022.toml with the "
                 "pipeline's calibrated\n# soil-soil rolling friction and surface energy "
                 "per moisture.\n" + model)
        # The same model as last time and its validation finished: keep it (resuming).
        done = (path.exists() and path.read_text() == model
                and (self.out / "validation" / "compare.json").exists())
        path.write_text(model)
        coarse = "--coarse" if at_coarse_preset() else None
        argv = ["compare", "--model", path, "--data", REPO / "data" / "li2022" / "measurements.csv",
                "--tests", "repose", "--replicates", self.replicates, "--cores", self.cores,
                "--out", self.out / "validation", "--quiet"]
        if coarse:
            argv.append(coarse)
        if not done:
            self.run(*argv)
        rows = json.loads((self.out / "validation" / "compare.json").read_text())["rows"]
        study = {int(r["moisture_pct"]): r for r in read_csv(DATA / "table11_calibrated_contact.csv")}
        self.h("Validation: the calibrated model's funnel test against table 1")
        self.p(f"`tilth compare` with OUT/model.toml, {self.replicates} seeds per moisture "
               "(mean +- standard deviation between seeds; the standard error of the mean is "
               "sd / sqrt(seeds)):")
        self.p()
        self.p("| moisture | measured | study simulated (error) | tilth mean +- sd | s.e. of mean | tilth error |")
        self.p("|---|---|---|---|---|---|")
        worst = 0.0
        for r in rows:
            m = int(r["conditions"]["moisture_pct"])
            sims = [v for v in r["simulated"] if v is not None]
            sd = r.get("simulated_scatter")
            se = sd / math.sqrt(len(sims)) if sd and sims else None
            meas = r["value"]
            s_sim = float(study[m]["simulated_repose_angle_deg"])
            err = 100 * r["relative_error"] if r["relative_error"] is not None else None
            if err is not None:
                worst = max(worst, abs(err))
            self.p(f"| {m} % | {meas:.2f} | {s_sim:.2f} ({100 * (s_sim - meas) / meas:+.2f} %) | "
                   f"{fmt(r['simulated_mean'])} +- {fmt(sd)} | {fmt(se)} | "
                   f"{'-' if err is None else f'{err:+.2f} %'} |")
        self.p()
        self.p(f"Worst error: tilth {worst:.2f} %, the study 4.72 % (its table 11 at 12 %).")

    # 6. The angle calibrated on the quiet funnel heap ---------------------------------------
    def calibrate_repose(self, model, surface_seeds, check_seeds):
        """`tilth calibrate` per moisture on the quiet heap, then fresh seeds through compare.

        The study's route above (one run per design point) cannot hold 2 % at the coarse scale:
        its heaps scatter by 5-7 degrees between seeds. The quiet heap scatters by 1-3, and
        `tilth calibrate` measures that scatter (`surface_seeds` per surface setting, then
        direct checks of `check_seeds` seeds, seeds 1001 on, at the solved setting, refined by
        Newton steps while the check misses). The calibrated model is then run once more by
        `tilth compare` with `--replicates` seeds (2001 on, used by no calibration run), whose mean is
        the verdict: the calibration chose its setting by its own checks, so those do not
        count as validation.
        """
        sets = []
        for key, value in QUIET_FUNNEL:
            sets += ["--set", f"repose.{key}={value}"]
        cal = self.out / "repose-calibration"
        measurements = REPO / "data" / "li2022" / "measurements.csv"
        self.run("calibrate", "--model", model, "--data", measurements, "--test", "repose",
                 "--param", self.repose_param, "--seeds", surface_seeds, "--check-seeds", check_seeds,
                 "--refine", 2, "--coarse", *sets, "--out", cal, "--cores", self.cores)
        calibration = json.loads((cal / "calibration.json").read_text())
        self.run("compare", "--model", cal / "model.toml", "--data", measurements,
                 "--tests", "repose", "--replicates", self.replicates,
                 "--first-seed", VALIDATION_FIRST_SEED, "--coarse", *sets,
                 "--cores", self.cores, "--out", self.out / "repose-validation")
        rows = json.loads((self.out / "repose-validation" / "compare.json").read_text())["rows"]
        study = {int(r["moisture_pct"]): r for r in read_csv(DATA / "table11_calibrated_contact.csv")}
        shown = Path(model).resolve()
        shown = shown.relative_to(REPO) if shown.is_relative_to(REPO) else shown
        self.h("The angle calibrated on the quiet funnel heap")
        self.p(f"`tilth calibrate` from `{shown}`, the free parameter `{self.repose_param}` per "
               f"moisture, {surface_seeds} seeds per surface setting and {check_seeds} per direct "
               f"check; then `tilth compare` with the calibrated model and {self.replicates} fresh "
               f"seeds per moisture (from {VALIDATION_FIRST_SEED}). The funnel: "
               + ", ".join(f"{k} = {v}" for k, v in QUIET_FUNNEL) + " at the coarse preset. "
               "Mean +- sd between seeds; s.e. = sd / sqrt(seeds).")
        self.p()
        self.p("| moisture | measured | study simulated (error) | calibrated rolling friction (95 % posterior) "
               "| check: mean +- sd (seeds) | validation: mean +- sd | s.e. | validation error "
               f"| within {REPOSE_TOLERANCE:g} % |")
        self.p("|---|---|---|---|---|---|---|---|---|")
        errors, inside = [], 0
        for m in MOISTURES:
            s_sim = float(study[m]["simulated_repose_angle_deg"])
            c = next((c for c in calibration["conditions"]
                      if abs(c["conditions"].get("moisture_pct", -1) - m) < 1e-9), None)
            r = next((r for r in rows if abs(r["conditions"]["moisture_pct"] - m) < 1e-9), None)
            if c is None or r is None:
                self.p(f"| {m} % | | {s_sim:.2f} | not calibrated | | | | | no |")
                continue
            meas = r["value"]
            s_err = 100 * (s_sim - meas) / meas
            post = c["posterior"]
            check = c["iterations"][-1] if c["iterations"] else None
            check_text = (f"{check['mean']:.2f} +- {fmt(check['sd'])} ({len(check['values'])})"
                          if check else "-")
            sd, se, err, ok = row_stats(r, REPOSE_TOLERANCE)
            if err is not None:
                errors.append(abs(err))
            inside += ok
            self.p(f"| {m} % | {meas:.2f} | {s_sim:.2f} ({s_err:+.2f} %) | "
                   f"{c['calibrated'][0]:.3f} ({post['q025'][0]:.3f}-{post['q975'][0]:.3f}) | "
                   f"{check_text} | {fmt(r['simulated_mean'])} +- {fmt(sd)} | {fmt(se)} | "
                   f"{'-' if err is None else f'{err:+.2f} %'} | {'yes' if ok else 'no'} |")
        self.p()
        worst = max(errors) if errors else float("nan")
        line = (f"{inside} of {len(MOISTURES)} moistures within {REPOSE_TOLERANCE:g} % on fresh "
                f"seeds; worst error tilth {worst:.2f} %, the study 4.72 % (its table 11 at 12 %).")
        self.p(line)
        return line

    # 7. The moistures the validation missed, refined ---------------------------------------
    def refine_repose(self, surface_seeds, check_seeds, seeds):
        """The moistures whose validation (stage `repose-calibration`) missed by more than the
        tolerance, refined with what those runs measured, then validated on `seeds` fresh
        seeds each (3001 on).

        - A calibrated rolling friction inside its range: one Newton step from every run at
          that setting (the calibration's last check and the validation, pooled), along the
          slope between the calibration's last two checks (the same seeds at two settings:
          common random numbers, so the slope is not blurred by the scatter between seeds).
        - At an end of its range (where the angle no longer follows it): `tilth calibrate`
          at that moisture with the surface energy free (REFINE_COHESION) and the rolling
          friction at the middle of its range.

        The other moistures keep their setting and their validation.
        """
        cal = self.out / "repose-calibration"
        calibration = json.loads((cal / "calibration.json").read_text())
        rows = json.loads((self.out / "repose-validation" / "compare.json").read_text())["rows"]
        lo, hi = (float(v) for v in self.repose_param.split("=")[1].split(":"))
        key = self.repose_param.split("=")[0].split(".")[1]
        ref = self.out / "repose-refinement"
        ref.mkdir(parents=True, exist_ok=True)
        sets = []
        for k, value in QUIET_FUNNEL:
            sets += ["--set", f"repose.{k}={value}"]
        model = (cal / "model.toml").read_text()
        steps, clamped, before = {}, [], {}
        for m in MOISTURES:
            c = next(c for c in calibration["conditions"]
                     if abs(c["conditions"]["moisture_pct"] - m) < 1e-9)
            r = next(r for r in rows if abs(r["conditions"]["moisture_pct"] - m) < 1e-9)
            before[m] = r
            if abs(100 * r["relative_error"]) <= REPOSE_TOLERANCE:
                continue
            x = c["calibrated"][0]
            if lo < x < hi:
                steps[m] = pooled_newton(c["iterations"], r["simulated"], r["value"], lo, hi)
            else:
                clamped.append(m)
        for m in clamped:
            model = set_interpolated(model, "soil-soil", key, m, 0.5 * (lo + hi),
                                     f"{m} %: the middle of the range (repose-refinement)")
        cohesion = {}
        for m in clamped:
            start = ref / f"start-{m}.toml"
            start.write_text(model)
            out = ref / f"calibrate-{m}"
            self.run("calibrate", "--model", start, "--data", REPO / "data" / "li2022" / "measurements.csv",
                     "--test", "repose", "--where", f"moisture_pct={m}", "--param", REFINE_COHESION,
                     "--seeds", surface_seeds, "--check-seeds", check_seeds, "--refine", 1,
                     "--coarse", *sets, "--out", out, "--cores", self.cores)
            model = (out / "model.toml").read_text()
            got = json.loads((out / "calibration.json").read_text())["conditions"][0]
            cohesion[m] = got
        for m, step in steps.items():
            if step is not None:
                model = set_interpolated(model, "soil-soil", key, m, step["setting"],
                                         f"{m} %: a pooled Newton step (repose-refinement)")
        (ref / "model.toml").write_text(model)
        changed = sorted(cohesion) + sorted(m for m, st in steps.items() if st is not None)
        after = {}
        if changed:
            data = ref / "measurements.csv"
            lines = (REPO / "data" / "li2022" / "measurements.csv").read_text().splitlines()
            keep = [ln for ln in lines[1:] if ln.startswith("repose,")
                    and int(float(ln.split(",")[1])) in changed]
            data.write_text("\n".join([lines[0], *keep]) + "\n")
            self.run("compare", "--model", ref / "model.toml", "--data", data, "--tests", "repose",
                     "--replicates", seeds, "--first-seed", REFINEMENT_FIRST_SEED, "--coarse", *sets,
                     "--cores", self.cores, "--out", ref / "validation")
            for r in json.loads((ref / "validation" / "compare.json").read_text())["rows"]:
                after[int(round(r["conditions"]["moisture_pct"]))] = r
        self.h("The moistures the validation missed, refined")
        self.p(f"Moistures whose validation missed by more than {REPOSE_TOLERANCE:g} %: a Newton step "
               "from every run at the calibrated setting (last check and validation pooled) along the "
               "slope between the last two checks (same seeds), or, where the rolling friction sat at "
               f"an end of its range, `tilth calibrate` with `{REFINE_COHESION}` at that moisture. "
               f"Then {seeds} fresh seeds each (from {REFINEMENT_FIRST_SEED}); the other moistures "
               "keep their setting and their validation.")
        self.p()
        self.p("| moisture | measured | validation before | refinement | validation after: mean +- sd (seeds) "
               f"| s.e. | error | within {REPOSE_TOLERANCE:g} % |")
        self.p("|---|---|---|---|---|---|---|---|")
        inside, worst = 0, 0.0
        for m in MOISTURES:
            b = before[m]
            _, _, b_err, _ = row_stats(b, REPOSE_TOLERANCE)
            if m in after:
                r = after[m]
                if m in cohesion:
                    g = cohesion[m]
                    how = (f"surface energy {g['calibrated'][0]:.4f} J/m^2, rolling friction "
                           f"{0.5 * (lo + hi):g} (check {g['simulated_mean']:.2f}, {len(g['iterations'][-1]['values'])} seeds)")
                else:
                    st = steps[m]
                    how = (f"rolling friction {st['from']:.4f} -> {st['setting']:.4f} (pooled "
                           f"{st['pooled_mean']:.2f} over {st['pooled']} runs, slope {st['slope']:.1f} deg per unit)")
            else:
                r, how = b, ("no step: no two checks to take a slope from" if m in steps else "kept")
            sd, se, err, ok = row_stats(r, REPOSE_TOLERANCE)
            inside += ok
            worst = max(worst, abs(err)) if err is not None else worst
            n = len([v for v in r["simulated"] if v is not None])
            self.p(f"| {m} % | {r['value']:.2f} | {b_err:+.2f} % | {how} | "
                   f"{fmt(r['simulated_mean'])} +- {fmt(sd)} ({n}) | {fmt(se)} | "
                   f"{'-' if err is None else f'{err:+.2f} %'} | {'yes' if ok else 'no'} |")
        self.p()
        line = (f"{inside} of {len(MOISTURES)} moistures within {REPOSE_TOLERANCE:g} % on fresh seeds "
                f"after the refinement; worst error {worst:.2f} % (the study: 4.72 %).")
        self.p(line)
        return line

    # 8. Bonds: tables 12 and 13 ----------------------------------------------------------
    def bonds(self, model, replicates):
        """The shear box and the UCS test at every condition of tables 12 and 13.

        The bond strengths come from `model`, calibrated beforehand (per test and condition:
        a sweep over the bond shear strength, `tilth rsm fit` / `solve`, checked with
        `tilth compare`; docs/li2022-statistics.md). This stage re-runs every specimen with
        fresh runs of this build and puts the result beside the study's tables.
        """
        coarse = at_coarse_preset()
        argv = ["compare", "--model", model, "--data", REPO / "data" / "li2022" / "measurements.csv",
                "--tests", "direct_shear,ucs", "--replicates", replicates,
                "--cores", self.cores, "--out", self.out / "bonds"]
        # Not --quiet: these runs take minutes each, and compare shows them finishing (a bar
        # on a terminal, one line per run in a log).
        if coarse:
            argv.append("--coarse")
        self.run(*argv)
        rows = json.loads((self.out / "bonds" / "compare.json").read_text())["rows"]
        shown = Path(model).resolve()
        shown = shown.relative_to(REPO) if shown.is_relative_to(REPO) else shown
        scale = "the coarse preset (4 mm grains)" if coarse else "the study's scale (2 mm grains)"
        summary = []
        for test, observable, number, csv_name, meas_col, sim_col, band in BOND_TABLES:
            study = read_csv(DATA / csv_name)
            self.h(f"Table {number}: {'peak shear force' if test == 'direct_shear' else 'unconfined compressive strength'}"
                   ", the study's simulation and tilth's")
            if test == "direct_shear":
                self.p(f"`tilth compare` with `{shown}`, {replicates} specimens (seeds) per "
                       f"condition, at {scale}; the study's error band is {band} % (its worst "
                       "row). Mean +- sd between specimens; s.e. = sd / sqrt(specimens).")
                self.p()
            unit = "N" if test == "direct_shear" else "kPa"
            self.p(f"| moisture | firmness MPa | measured {unit} | study simulated (error) | "
                   f"tilth mean +- sd | s.e. | tilth error | within {band} % |")
            self.p("|---|---|---|---|---|---|---|---|")
            errors, study_errors, inside = [], [], 0
            for s in study:
                m, f = float(s["moisture_pct"]), float(s["firmness_mpa"])
                r = next((r for r in rows if r["test"] == test and r["observable"] == observable
                          and abs(r["conditions"]["moisture_pct"] - m) < 1e-9
                          and abs(r["conditions"]["firmness_mpa"] - f) < 1e-9), None)
                meas, s_sim = float(s[meas_col]), float(s[sim_col])
                s_err = 100 * (s_sim - meas) / meas
                study_errors.append(abs(s_err))
                if r is None:
                    self.p(f"| {m:g} % | {f:g} | {meas:.2f} | {s_sim:.2f} ({s_err:+.2f} %) | "
                           "not in the measurements | | | |")
                    continue
                sd, se, err, ok = row_stats(r, band)
                if err is not None:
                    errors.append(abs(err))
                inside += ok
                self.p(f"| {m:g} % | {f:g} | {meas:.2f} | {s_sim:.2f} ({s_err:+.2f} %) | "
                       f"{fmt(r['simulated_mean'])} +- {fmt(sd)} | {fmt(se)} | "
                       f"{'-' if err is None else f'{err:+.2f} %'} | {'yes' if ok else 'no'} |")
            self.p()
            mae = sum(errors) / len(errors) if errors else float("nan")
            s_mae = sum(study_errors) / len(study_errors)
            line = (f"{inside} of {len(study)} rows within {band} %; mean absolute error "
                    f"tilth {mae:.2f} %, the study {s_mae:.2f} %.")
            self.p(line)
            summary.append(line)
        return summary

    def write(self):
        head = ["# The reference study as a tilth pipeline: its tables beside tilth's own runs",
                "",
                "Written by `sweeps/li2022/pipeline.py`. Every number on tilth's side comes from "
                "the runs under this directory; the study's numbers from "
                "`sweeps/li2022/data/` (its tables as CSV)."]
        text = "\n".join(head + self.report) + "\n"
        # Paths relative to the repository, so that the report reads the same anywhere.
        text = text.replace(str(REPO) + "/", "")
        (self.out / "report.md").write_text(text)
        print(f"report: {self.out / 'report.md'}", file=sys.stderr)


def set_pair_key(model, pair, key, value):
    """Replaces `key = ...` (one line) inside `[pairs.PAIR]` of a model file."""
    section = re.search(rf"^\[pairs\.{re.escape(pair)}\]\n(.*?)(?=^\[)", model, re.S | re.M)
    if not section:
        sys.exit(f"pipeline: models/li2022.toml has no [pairs.{pair}]")
    body = section.group(1)
    new, n = re.subn(rf"^{key}\s*=.*$(\n[ \t]+#.*$)*", f"{key} = {value}", body, count=1, flags=re.M)
    if n != 1:
        sys.exit(f"pipeline: [pairs.{pair}] has no `{key}`")
    return model[:section.start(1)] + new + model[section.end(1):]


def pooled_newton(iterations, validation, target, lo, hi):
    """One Newton step for a calibrated setting whose validation missed: the mean of every run
    at the last check's setting (the check's values and the validation's, pooled), moved to
    `target` along the slope between the last two checks, which ran the same seeds at two
    settings. None without two such checks."""
    if len(iterations) < 2:
        return None
    a, b = iterations[-2], iterations[-1]
    if len(a["values"]) != len(b["values"]) or a["setting"][0] == b["setting"][0]:
        return None
    slope = (a["mean"] - b["mean"]) / (a["setting"][0] - b["setting"][0])
    if slope == 0:
        return None
    pool = list(b["values"]) + [v for v in validation if v is not None]
    mean = sum(pool) / len(pool)
    x = b["setting"][0]
    new = round(min(hi, max(lo, x + (target - mean) / slope)), 4)
    return {"from": x, "setting": new, "slope": slope, "pooled": len(pool), "pooled_mean": mean}


def set_interpolated(model, pair, key, at, value, note):
    """Sets the `y` of `key = { interpolate = ..., x = [...], y = [...] }` in `[pairs.PAIR]`
    at the `x` equal to `at` (one line), and says so in the line's comment (`note`)."""
    section = re.search(rf"^\[pairs\.{re.escape(pair)}\]\n(.*?)(?=^\[)", model, re.S | re.M)
    if not section:
        sys.exit(f"pipeline: the model has no [pairs.{pair}]")
    body = section.group(1)
    line = re.search(rf"^{key}\s*=\s*{{\s*interpolate.*$", body, re.M)
    if not line:
        sys.exit(f"pipeline: [pairs.{pair}].{key} is not an interpolate table on one line")
    xs = re.search(r"\bx\s*=\s*\[([^\]]*)\]", line.group(0))
    ys = re.search(r"\by\s*=\s*\[([^\]]*)\]", line.group(0))
    x = [float(v) for v in xs.group(1).split(",")]
    y = [v.strip() for v in ys.group(1).split(",")]
    hit = [i for i, v in enumerate(x) if abs(v - at) < 1e-9]
    if not hit:
        sys.exit(f"pipeline: [pairs.{pair}].{key} has no point at {at}")
    y[hit[0]] = f"{value:g}"
    text = line.group(0)
    text = text[:ys.start(1)] + ", ".join(y) + text[ys.end(1):]
    text += f"; {note}" if "#" in text else f"  # {note}"
    body = body[:line.start()] + text + body[line.end():]
    return model[:section.start(1)] + body + model[section.end(1):]


def row_stats(r, band=None):
    """A compare.json row's sd between seeds, standard error of the mean, relative error in
    %, and whether that error is within `band` % (None: no band)."""
    sims = [v for v in r["simulated"] if v is not None]
    sd = r.get("simulated_scatter")
    se = sd / math.sqrt(len(sims)) if sd is not None and sims else None
    err = 100 * r["relative_error"] if r["relative_error"] is not None else None
    ok = err is not None and band is not None and abs(err) <= band
    return sd, se, err, ok


def sign(v):
    """A coded level as Design-Expert prints it: -1, 0, +1."""
    x = float(v)
    return "0" if x == 0 else f"{x:+.0f}"


def fmt(v):
    if v is None or v == "":
        return "-"
    try:
        return f"{float(v):.2f}"
    except ValueError:
        return str(v)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("out", help="output directory")
    ap.add_argument("--cores", type=int, default=2)
    ap.add_argument("--replicates", type=int, default=10,
                    help="seeds per moisture in the validation runs")
    ap.add_argument("--bonds", default=str(REPO / "models" / "li2022-per-test-bonds.toml"),
                    help="model file with calibrated bond strengths for tables 12 and 13")
    ap.add_argument("--bond-replicates", type=int, default=3,
                    help="specimens (seeds) per condition of tables 12 and 13")
    ap.add_argument("--stages", default=",".join(STAGES),
                    help="comma-separated, of: " + ", ".join(STAGES) + " (default: all, in this order)")
    ap.add_argument("--repose-model", default=str(REPOSE_MODEL),
                    help="starting model of the repose-calibration stage (default: the twisting model; "
                         "models/li2022-repose.toml is the one without twisting, "
                         "calibrated with soil-soil.rolling_friction=0.1:0.6)")
    ap.add_argument("--repose-param", default=REPOSE_PARAM,
                    help="free parameter and range of the repose-calibration and -refinement stages, PAIR.KEY=LO:HI "
                         f"(default {REPOSE_PARAM})")
    ap.add_argument("--surface-seeds", type=int, default=2,
                    help="seeds per surface setting in the repose-calibration stage")
    ap.add_argument("--check-seeds", type=int, default=10,
                    help="seeds per direct check in the repose-calibration stage")
    ap.add_argument("--refinement-check-seeds", type=int, default=12,
                    help="seeds per direct check in the repose-refinement stage")
    ap.add_argument("--refinement-seeds", type=int, default=20,
                    help="fresh seeds per refined moisture in the repose-refinement stage")
    ap.add_argument("--tilth", default=shutil.which("tilth") or "tilth")
    args = ap.parse_args()
    stages = [t.strip() for t in args.stages.split(",") if t.strip()]
    unknown = [t for t in stages if t not in STAGES]
    if unknown or not stages:
        ap.error(f"--stages: `{','.join(unknown) or args.stages}` is unknown: allowed "
                 + ", ".join(STAGES))
    for name in ("replicates", "bond_replicates", "surface_seeds", "check_seeds", "cores",
                 "refinement_check_seeds", "refinement_seeds"):
        if getattr(args, name) < 1:
            ap.error(f"--{name.replace('_', '-')}: {getattr(args, name)} is out of range: at least 1")
    if "bonds" in stages and not Path(args.bonds).is_file():
        ap.error(f"--bonds: {args.bonds} is not a file")
    if "repose-calibration" in stages and not Path(args.repose_model).is_file():
        ap.error(f"--repose-model: {args.repose_model} is not a file")
    if not re.fullmatch(r"[\w-]+\.\w+=[-+.\deE]+:[-+.\deE]+", args.repose_param):
        ap.error(f"--repose-param: `{args.repose_param}` is not PAIR.KEY=LO:HI, "
                 f"e.g. {REPOSE_PARAM}")
    pipe = Pipeline(args)
    if "repose" in stages:
        pipe.screening()
        nxt = pipe.steepest_ascent()
        pipe.box_behnken(nxt)
        chosen = pipe.solve(nxt)
        pipe.validate(chosen)
    if "repose-calibration" in stages:
        pipe.calibrate_repose(args.repose_model, args.surface_seeds, args.check_seeds)
    if "repose-refinement" in stages:
        pipe.refine_repose(args.surface_seeds, args.refinement_check_seeds, args.refinement_seeds)
    if "bonds" in stages:
        pipe.bonds(args.bonds, args.bond_replicates)
    pipe.write()


if __name__ == "__main__":
    main()
