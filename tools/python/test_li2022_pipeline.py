#!/usr/bin/env python3
"""Tests for the bond stage of sweeps/li2022/pipeline.py (tables 12 and 13).

    python3 -m unittest discover -s tools/python -p 'test_*.py' -v

The stage runs `tilth compare` and sets its rows beside the study's tables. Here `tilth` is
replaced by a stand-in that writes a compare.json with known errors, so that the table's
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


class BondStage(unittest.TestCase):
    def setUp(self):
        self.pipeline = load_pipeline()
        self.tmp = tempfile.TemporaryDirectory()
        out = Path(self.tmp.name)
        args = type("Args", (), {"out": str(out), "tilth": "tilth", "cores": 1,
                                 "replicates": 1})()
        self.pipe = self.pipeline.Pipeline(args)
        self.calls = []

        def run(*argv, capture=None):
            self.calls.append([str(a) for a in argv])
            fake_compare(out)
            return ""

        self.pipe.run = run
        self.summary = self.pipe.bonds(REPO / "docs" / "li2022-statistics" / "per-test-bonds.toml", 3)
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


if __name__ == "__main__":
    unittest.main()
