#!/usr/bin/env python3
"""Tests for the bond and repose-calibration stages of sweeps/li2022/pipeline.py.

    python3 -m unittest discover -s tools/python -p 'test_*.py' -v

The stages run `tilth calibrate` and `tilth compare` and set their rows beside the study's
tables. Here `tilth` is replaced by a stand-in that writes a calibration.json and a
compare.json with known errors, so that the table's
matching of rows, its errors, its band verdicts and its summaries are checked against
numbers made up for the test and against the errors the study itself printed.
"""

from __future__ import annotations

import csv
import importlib.util
import json
import re
import tempfile
import unittest
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
HERE = Path(__file__).resolve().parent
DATA = REPO / "sweeps" / "li2022" / "data"


def load_pipeline():
    spec = importlib.util.spec_from_file_location("li2022_pipeline",
                                                  REPO / "sweeps" / "li2022" / "pipeline.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def rows_of(name):
    with open(DATA / name, newline="") as f:
        return list(csv.DictReader(f))


# Relative errors made up for the test, per (test, moisture, firmness): one shear row and
# one UCS row outside the study's bands (6.53 % and 8.07 %), the others inside.
ERRORS = {
    ("direct_shear", 6, 0.34): -0.02, ("direct_shear", 6, 0.945): 0.01,
    ("direct_shear", 6, 1.55): 0.0, ("direct_shear", 6, 2.155): -0.03,
    ("direct_shear", 6, 2.76): 0.10, ("direct_shear", 3, 1.55): 0.04,
    ("direct_shear", 9, 1.55): -0.06, ("direct_shear", 12, 1.55): 0.02,
    ("ucs", 6, 0.34): 0.05, ("ucs", 6, 0.945): -0.09, ("ucs", 6, 1.55): 0.0,
    ("ucs", 6, 2.155): 0.03, ("ucs", 6, 2.76): 0.01, ("ucs", 3, 1.55): 0.08,
    ("ucs", 9, 1.55): -0.04, ("ucs", 12, 1.55): 0.02,
}


def fake_compare(out: Path):
    """compare.json as `tilth compare` writes it, with three specimens per row."""
    rows = []
    tables = [("direct_shear", "peak_shear_force_n", "table12_shear_peak_force.csv",
               "peak_shear_force_measured_n"),
              ("ucs", "ucs_kpa", "table13_ucs_peak.csv", "measured_value")]
    # Listed in another order than the study's tables: the stage must match by conditions.
    for test, observable, name, col in reversed(tables):
        for s in reversed(rows_of(name)):
            m, f = float(s["moisture_pct"]), float(s["firmness_mpa"])
            meas = float(s[col])
            mean = meas * (1 + ERRORS[(test, int(m), f)])
            sims = [mean - 1.0, mean, mean + 1.0]
            rows.append({
                "test": test, "observable": observable, "value": meas,
                "conditions": {"moisture_pct": m, "firmness_mpa": f},
                "simulated": sims, "simulated_mean": mean, "simulated_scatter": 1.0,
                "relative_error": (mean - meas) / meas,
            })
    (out / "bonds").mkdir(parents=True, exist_ok=True)
    (out / "bonds" / "compare.json").write_text(json.dumps({"rows": rows}))


def stand_in(case, cores, replicates, fake):
    """Gives `case` a pipeline in a temporary OUT whose `tilth` is a stand-in: every call's
    arguments go to `case.calls`, then `fake(argv)` writes the files tilth would have."""
    case.pipeline = load_pipeline()
    case.tmp = tempfile.TemporaryDirectory()
    case.out = Path(case.tmp.name)
    args = type("Args", (), {"out": str(case.out), "tilth": "tilth", "cores": cores,
                             "replicates": replicates,
                             "repose_param": case.pipeline.REPOSE_PARAM})()
    case.pipe = case.pipeline.Pipeline(args)
    case.calls = []

    def run(*argv, capture=None):
        argv = [str(a) for a in argv]
        case.calls.append(argv)
        fake(argv)
        return ""

    case.pipe.run = run


class BondStage(unittest.TestCase):
    def setUp(self):
        stand_in(self, 1, 1, lambda argv: fake_compare(self.out))
        self.summary = self.pipe.bonds(REPO / "models" / "li2022-per-test-bonds.toml", 3)
        self.report = "\n".join(self.pipe.report)

    def tearDown(self):
        self.tmp.cleanup()

    def table_rows(self, number):
        """The report's rows of table `number`: {(moisture, firmness): cells}."""
        part = self.report.split(f"## Table {number}:")[1].split("\n## ")[0]
        out = {}
        for line in part.splitlines():
            cells = [c.strip() for c in line.strip("|").split("|")]
            if len(cells) == 8 and cells[0].endswith("%") and cells[0][0].isdigit():
                out[(float(cells[0].rstrip(" %")), float(cells[1]))] = cells
        return out

    def test_it_runs_compare_on_the_bonded_tests_with_the_model_and_specimens_asked_for(self):
        self.assertEqual(len(self.calls), 1)
        argv = self.calls[0]
        self.assertEqual(argv[0], "compare")
        self.assertEqual(argv[argv.index("--tests") + 1], "direct_shear,ucs")
        self.assertEqual(argv[argv.index("--replicates") + 1], "3")
        self.assertTrue(argv[argv.index("--model") + 1].endswith("per-test-bonds.toml"))
        self.assertIn("--coarse", argv)  # pb.toml runs at the coarse preset

    def test_every_row_of_both_tables_gets_its_own_simulation_and_verdict(self):
        for number, test, band in ((12, "direct_shear", 6.53), (13, "ucs", 8.07)):
            rows = self.table_rows(number)
            self.assertEqual(len(rows), 8, self.report)
            for (m, f), cells in rows.items():
                e = 100 * ERRORS[(test, int(m), f)]
                self.assertEqual(cells[6], f"{e:+.2f} %", cells)
                self.assertEqual(cells[7], "yes" if abs(e) <= band else "no", cells)
                # s.e. of three specimens at sd 1.0
                self.assertEqual(cells[5], f"{1 / 3 ** 0.5:.2f}")

    def test_the_study_column_reproduces_the_errors_the_study_printed(self):
        for number, name in ((12, "table12_shear_peak_force.csv"), (13, "table13_ucs_peak.csv")):
            rows = self.table_rows(number)
            for s in rows_of(name):
                cells = rows[(float(s["moisture_pct"]), float(s["firmness_mpa"]))]
                printed = float(re.search(r"\(([-+][0-9.]+) %\)", cells[3]).group(1))
                self.assertAlmostEqual(abs(printed), float(s["error_pct"]), delta=0.011, msg=cells)

    def test_the_summaries_count_the_rows_inside_the_band_and_average_the_errors(self):
        shear = [abs(v) for (t, _, _), v in ERRORS.items() if t == "direct_shear"]
        ucs = [abs(v) for (t, _, _), v in ERRORS.items() if t == "ucs"]
        study12 = sum(float(s["error_pct"]) for s in rows_of("table12_shear_peak_force.csv")) / 8
        study13 = sum(float(s["error_pct"]) for s in rows_of("table13_ucs_peak.csv")) / 8
        self.assertEqual(len(self.summary), 2)
        self.assertTrue(self.summary[0].startswith("7 of 8 rows within 6.53 %"), self.summary)
        self.assertTrue(self.summary[1].startswith("7 of 8 rows within 8.07 %"), self.summary)
        self.assertIn(f"tilth {100 * sum(shear) / 8:.2f} %", self.summary[0])
        self.assertIn(f"tilth {100 * sum(ucs) / 8:.2f} %", self.summary[1])
        # The study's own mean error, from its printed column (rounded to 0.01 per row).
        got12 = float(re.search(r"the study ([0-9.]+) %", self.summary[0]).group(1))
        got13 = float(re.search(r"the study ([0-9.]+) %", self.summary[1]).group(1))
        self.assertAlmostEqual(got12, study12, delta=0.01)
        self.assertAlmostEqual(got13, study13, delta=0.01)


# The repose-calibration stage: made-up validation errors per moisture (one outside 2 %)
# and made-up calibrated rolling frictions.
ANGLE_ERRORS = {3: 0.012, 6: -0.004, 9: 0.031, 12: -0.015}
ROLLING = {3: 0.21, 6: 0.27, 9: 0.33, 12: 0.48}


def measured_angles():
    return {int(r["moisture_pct"]): float(r["repose_angle_deg"])
            for r in rows_of("table01_friction_repose.csv")}


def fake_calibration(out: Path):
    conditions = []
    for m, rf in ROLLING.items():
        meas = measured_angles()[m]
        conditions.append({
            "conditions": {"moisture_pct": float(m)}, "measured": meas, "calibrated": [rf],
            "iterations": [{"setting": [rf], "values": [meas] * 10, "mean": meas + 0.1,
                            "sd": 1.25, "error_pct": 0.0}],
            "posterior": {"q025": [rf - 0.05], "q975": [rf + 0.05]},
        })
    (out / "repose-calibration").mkdir(parents=True, exist_ok=True)
    (out / "repose-calibration" / "calibration.json").write_text(
        json.dumps({"conditions": list(reversed(conditions))}))


def fake_angle_compare(out: Path, seeds: int):
    rows = []
    for m, e in ANGLE_ERRORS.items():
        meas = measured_angles()[m]
        mean = meas * (1 + e)
        rows.append({"test": "repose", "observable": "repose_angle_deg", "value": meas,
                     "conditions": {"moisture_pct": float(m)},
                     "simulated": [mean - 1.0, mean + 1.0] * (seeds // 2),
                     "simulated_mean": mean, "simulated_scatter": 1.0,
                     "relative_error": e})
    (out / "repose-validation").mkdir(parents=True, exist_ok=True)
    (out / "repose-validation" / "compare.json").write_text(json.dumps({"rows": rows}))


class ReposeCalibrationStage(unittest.TestCase):
    def setUp(self):
        def fake(argv):
            if argv[0] == "calibrate":
                fake_calibration(self.out)
            else:
                fake_angle_compare(self.out, 8)

        stand_in(self, 2, 8, fake)
        self.line = self.pipe.calibrate_repose(REPO / "models" / "li2022-repose.toml", 2, 10)
        self.report = "\n".join(self.pipe.report)

    def tearDown(self):
        self.tmp.cleanup()

    def rows(self):
        part = self.report.split("## The angle calibrated on the quiet funnel heap")[1]
        out = {}
        for line in part.splitlines():
            cells = [c.strip() for c in line.strip("|").split("|")]
            if len(cells) == 9 and cells[0].endswith("%") and cells[0][0].isdigit():
                out[int(cells[0].rstrip(" %"))] = cells
        return out

    def sets(self, argv):
        return [argv[i + 1] for i, a in enumerate(argv) if a == "--set"]

    def test_it_calibrates_then_validates_the_calibrated_model_on_the_same_funnel(self):
        self.assertEqual([c[0] for c in self.calls], ["calibrate", "compare"])
        cal, cmp = self.calls
        self.assertEqual(cal[cal.index("--test") + 1], "repose")
        self.assertEqual(cal[cal.index("--param") + 1], self.pipeline.REPOSE_PARAM)
        self.assertEqual(cal[cal.index("--seeds") + 1], "2")
        self.assertEqual(cal[cal.index("--check-seeds") + 1], "10")
        self.assertNotIn("--where", cal)  # every moisture of table 1
        wanted = [f"repose.{k}={v}" for k, v in self.pipeline.QUIET_FUNNEL]
        self.assertEqual(self.sets(cal), wanted)
        self.assertEqual(self.sets(cmp), wanted)
        for argv in (cal, cmp):
            self.assertIn("--coarse", argv)
        self.assertEqual(Path(cmp[cmp.index("--model") + 1]),
                         self.out / "repose-calibration" / "model.toml")
        self.assertEqual(cmp[cmp.index("--replicates") + 1], "8")
        # Fresh seeds: none of the surface's (from 1, a few per setting) or the checks' (1001
        # to 1001 + check seeds - 1).
        first = int(cmp[cmp.index("--first-seed") + 1])
        self.assertGreaterEqual(first, 1001 + 10)

    def test_every_moisture_gets_its_setting_its_validation_error_and_a_verdict(self):
        rows = self.rows()
        self.assertEqual(sorted(rows), [3, 6, 9, 12], self.report)
        for m, cells in rows.items():
            e = 100 * ANGLE_ERRORS[m]
            self.assertTrue(cells[3].startswith(f"{ROLLING[m]:.3f} ("), cells)
            self.assertEqual(cells[4], f"{measured_angles()[m] + 0.1:.2f} +- 1.25 (10)")
            self.assertEqual(cells[6], f"{1 / 8 ** 0.5:.2f}")
            self.assertEqual(cells[7], f"{e:+.2f} %")
            self.assertEqual(cells[8], "yes" if abs(e) <= 2 else "no")

    def test_the_study_column_reproduces_the_errors_of_its_table_11(self):
        rows = self.rows()
        # The study's validation errors (docs/experiments.md): 0.7, 0.8, 0.7, 4.72 %.
        printed = {m: float(re.search(r"\(([-+][0-9.]+) %\)", rows[m][2]).group(1)) for m in rows}
        self.assertAlmostEqual(abs(printed[12]), 4.72, delta=0.01)
        for m in (3, 6, 9):
            self.assertLess(abs(printed[m]), 1.0)

    def test_the_summary_counts_moistures_within_2_percent_and_names_the_worst(self):
        self.assertTrue(self.line.startswith("3 of 4 moistures within 2 %"), self.line)
        self.assertIn("worst error tilth 3.10 %", self.line)

    def test_another_free_parameter_reaches_calibrate_and_the_report(self):
        # The twisting model's calibration (docs/li2022-repose-calibration.md) widens the range.
        self.calls.clear()
        self.pipe.report.clear()
        param = "soil-soil.rolling_friction=0.05:0.6"
        self.pipe.repose_param = param
        self.pipe.calibrate_repose(REPO / "models" / "li2022-repose-twisting.toml",
                                   2, 10)
        cal = self.calls[0]
        self.assertEqual(cal[0], "calibrate")
        self.assertEqual(cal[cal.index("--param") + 1], param)
        self.assertTrue(cal[cal.index("--model") + 1].endswith("li2022-repose-twisting.toml"))
        self.assertIn(f"the free parameter `{param}`", "\n".join(self.pipe.report))


# The repose-refinement stage: a calibration whose validation missed at 6 % (inside the range,
# two checks with the same seeds), at 9 % (one check only: no slope) and at 12 % (rolling
# friction at the end of its range); 3 % passed.
REFINE_ANGLES = {3: 32.76, 6: 35.53, 9: 37.89, 12: 43.87}
REFINE_BEFORE = {3: 0.010, 6: -0.035, 9: 0.025, 12: -0.027}


def fake_refinement_inputs(out: Path):
    def cond(m, its):
        return {"conditions": {"moisture_pct": float(m)}, "measured": REFINE_ANGLES[m],
                "calibrated": [its[-1]["setting"][0]], "iterations": its}

    def it(x, values):
        return {"setting": [x], "values": values, "mean": sum(values) / len(values)}

    conditions = [
        cond(3, [it(0.35, [32.0, 33.0])]),
        # slope (36.5 - 35.5) / (0.17 - 0.15) = 50 degrees per unit
        cond(6, [it(0.17, [36.0, 37.0]), it(0.15, [35.0, 36.0])]),
        cond(9, [it(0.13, [38.0, 39.0])]),
        cond(12, [it(0.5, [42.0, 43.0]), it(0.6, [43.0, 43.5])]),
    ]
    (out / "repose-calibration").mkdir(parents=True, exist_ok=True)
    (out / "repose-calibration" / "calibration.json").write_text(json.dumps({"conditions": conditions}))
    (out / "repose-calibration" / "model.toml").write_text(
        (HERE / "fixtures" / "repose-calibrated-model.toml").read_text())
    rows = []
    for m, e in REFINE_BEFORE.items():
        mean = REFINE_ANGLES[m] * (1 + e)
        rows.append({"test": "repose", "observable": "repose_angle_deg", "value": REFINE_ANGLES[m],
                     "conditions": {"moisture_pct": float(m)},
                     # 6 %: 34.0 and 34.5 with the check's 35.0 and 36.0 pool to 34.875
                     "simulated": [34.0, 34.5] if m == 6 else [mean - 1.0, mean + 1.0],
                     "simulated_mean": mean, "simulated_scatter": 1.0, "relative_error": e})
    (out / "repose-validation").mkdir(parents=True, exist_ok=True)
    (out / "repose-validation" / "compare.json").write_text(json.dumps({"rows": rows}))


class ReposeRefinementStage(unittest.TestCase):
    AFTER = {6: 0.004, 12: -0.011}

    def setUp(self):
        self.starts = []

        def fake(argv):
            out = Path(argv[argv.index("--out") + 1])
            out.mkdir(parents=True, exist_ok=True)
            if argv[0] == "calibrate":
                start = Path(argv[argv.index("--model") + 1]).read_text()
                self.starts.append(start)
                (out / "model.toml").write_text(start + "\n# surface energy calibrated\n")
                (out / "calibration.json").write_text(json.dumps({"conditions": [{
                    "calibrated": [0.1731], "simulated_mean": 43.9,
                    "iterations": [{"values": [43.9] * 12}]}]}))
            else:
                self.data = Path(argv[argv.index("--data") + 1]).read_text()
                rows = []
                for m, e in self.AFTER.items():
                    mean = REFINE_ANGLES[m] * (1 + e)
                    rows.append({"value": REFINE_ANGLES[m], "conditions": {"moisture_pct": float(m)},
                                 "simulated": [mean - 1.0, mean + 1.0] * 10, "simulated_mean": mean,
                                 "simulated_scatter": 1.0, "relative_error": e})
                (out / "compare.json").write_text(json.dumps({"rows": rows}))

        stand_in(self, 2, 10, lambda argv: None)
        fake_refinement_inputs(self.out)
        self.pipe.run = lambda *argv, capture=None: (self.calls.append([str(a) for a in argv]),
                                                     fake([str(a) for a in argv]))
        self.line = self.pipe.refine_repose(2, 12, 20)
        self.report = "\n".join(self.pipe.report)

    def tearDown(self):
        self.tmp.cleanup()

    def middle(self):
        """The middle of the pipeline's rolling friction range (REPOSE_PARAM)."""
        lo, hi = (float(v) for v in self.pipeline.REPOSE_PARAM.split("=")[1].split(":"))
        return 0.5 * (lo + hi)

    def rolling(self, model):
        line = next(ln for ln in model.splitlines() if ln.startswith("rolling_friction"))
        return [float(v) for v in re.search(r"\by = \[([^\]]*)\]", line).group(1).split(",")]

    def test_the_clamped_moisture_is_calibrated_on_its_cohesion_from_the_range_middle(self):
        cal = self.calls[0]
        self.assertEqual(cal[0], "calibrate")
        self.assertEqual(cal[cal.index("--where") + 1], "moisture_pct=12")
        self.assertEqual(cal[cal.index("--param") + 1], self.pipeline.REFINE_COHESION)
        self.assertEqual(cal[cal.index("--check-seeds") + 1], "12")
        before = self.rolling((self.out / "repose-calibration" / "model.toml").read_text())
        start = self.rolling(self.starts[0])
        self.assertEqual(start, before[:3] + [round(self.middle(), 6)])

    def test_the_moisture_inside_its_range_takes_one_newton_step_from_the_pooled_runs(self):
        # Pooled: the last check (35.0, 36.0) and the validation (34.0, 34.5): 34.875; slope
        # 50 per unit: 0.15 + (35.53 - 34.875) / 50 = 0.1631.
        final = self.rolling((self.out / "repose-refinement" / "model.toml").read_text())
        self.assertAlmostEqual(final[1], round(0.15 + (35.53 - 34.875) / 50, 4), places=9)
        self.assertEqual(final[3], round(self.middle(), 6))
        self.assertIn("# surface energy calibrated",
                      (self.out / "repose-refinement" / "model.toml").read_text())

    def test_only_the_refined_moistures_are_validated_on_fresh_seeds(self):
        cmp = self.calls[-1]
        self.assertEqual(cmp[0], "compare")
        self.assertEqual(cmp[cmp.index("--first-seed") + 1], "3001")
        self.assertEqual(cmp[cmp.index("--replicates") + 1], "20")
        rows = [ln for ln in self.data.splitlines()[1:]]
        self.assertEqual([r.split(",")[1] for r in rows], ["6", "12"])

    def test_the_report_keeps_the_others_and_says_why(self):
        cells = {}
        for line in self.report.splitlines():
            c = [x.strip() for x in line.strip("|").split("|")]
            if len(c) == 8 and c[0].endswith("%") and c[0][0].isdigit():
                cells[int(c[0].rstrip(" %"))] = c
        self.assertEqual(cells[3][3], "kept")
        self.assertEqual(cells[3][6], "+1.00 %")
        self.assertTrue(cells[9][3].startswith("no step"), cells[9])
        self.assertEqual(cells[6][6], "+0.40 %")
        self.assertIn("0.1500 -> 0.1631", cells[6][3])
        self.assertIn("surface energy 0.1731", cells[12][3])
        self.assertEqual(cells[12][7], "yes")
        self.assertEqual(cells[9][7], "no")
        self.assertTrue(self.line.startswith("3 of 4 moistures within 2 %"), self.line)
        self.assertIn("worst error 2.50 %", self.line)


if __name__ == "__main__":
    unittest.main()
