#!/usr/bin/env python3
"""Tests for tools/discovery/criterion_odds.py, the odds that a perfect model meets the issue's
"within 1.5x the injected noise".

    python3 -m unittest discover -s tools/python -p 'test_criterion_odds.py' -v

The chi^2 tail is checked against the tables' 95 % quantiles; the Monte Carlo against the closed
form where the two must agree (no run scatter: chi^2_n <= 2.25 n); the study reader against a
study made up here with hand-computable variances.
"""

from __future__ import annotations

import csv
import json
import random
import runpy
import tempfile
import unittest
from pathlib import Path
from types import SimpleNamespace

REPO = Path(__file__).resolve().parents[2]


def load():
    return SimpleNamespace(**runpy.run_path(str(REPO / "tools" / "discovery" / "criterion_odds.py")))


class Chi2(unittest.TestCase):
    def test_the_tail_at_the_tables_95_percent_quantiles(self):
        m = load()
        # chi^2 95 % quantiles (Abramowitz and Stegun, table 26.8), even and odd dof.
        for k, q in [(1, 3.8415), (2, 5.9915), (3, 7.8147), (4, 9.4877), (7, 14.0671), (16, 26.2962)]:
            self.assertAlmostEqual(m.chi2_survival(q, k), 0.05, places=4, msg=f"k = {k}")

    def test_the_tail_is_one_at_zero_and_falls(self):
        m = load()
        self.assertEqual(m.chi2_survival(0.0, 5), 1.0)
        self.assertGreater(m.chi2_survival(4.0, 5), m.chi2_survival(6.0, 5))

    def test_more_conditions_make_the_bar_safer(self):
        m = load()
        odds = [m.perfect_pass(n) for n in (4, 7, 16)]
        self.assertEqual(odds, sorted(odds))
        self.assertAlmostEqual(odds[0], 1 - m.chi2_survival(9.0, 4))


class MonteCarlo(unittest.TestCase):
    def test_without_run_scatter_it_is_the_closed_form(self):
        m = load()
        rows = [(0.5, 0.25)] * 7  # sigma 0.5, variance sigma^2: infinitely many runs
        p = m.pass_odds(rows, 40000, random.Random(3))
        # 40,000 draws: the binomial sd of a share near 0.97 is under 0.001.
        self.assertAlmostEqual(p, m.perfect_pass(7), delta=0.004)

    def test_run_scatter_lowers_the_odds(self):
        m = load()
        clean = m.pass_odds([(1.0, 1.0)] * 4, 20000, random.Random(5))
        noisy = m.pass_odds([(1.0, 2.0)] * 4, 20000, random.Random(5))
        self.assertLess(noisy, clean - 0.2)


class Study(unittest.TestCase):
    def test_the_variances_add_noise_and_both_means_scatter(self):
        m = load()
        with tempfile.TemporaryDirectory() as tmp:
            study = Path(tmp) / "hidden-fines"
            (study / "5-truth").mkdir(parents=True)
            with open(study / "data.csv", "w", newline="") as f:
                w = csv.writer(f)
                w.writerow(["test", "moisture_pct", "observable", "value", "replicates"])
                w.writerow(["repose", "3", "heap_cone_angle_deg", "35.0", "4"])
                w.writerow(["repose", "3", "funnel_flow_rate_g_s", "400.0", "4"])
            rows = [{"observable": "heap_cone_angle_deg", "conditions": {"moisture_pct": 3.0},
                     "simulated_scatter": 2.0},
                    {"observable": "funnel_flow_rate_g_s", "conditions": {"moisture_pct": 3.0},
                     "simulated_scatter": 8.0}]
            (study / "5-truth" / "compare.json").write_text(json.dumps({"replicates": 16, "rows": rows}))
            spec = {"heap_cone_angle_deg": "0.5", "funnel_flow_rate_g_s": "2%"}
            v = m.reading_variances(str(study), spec)
        # Cone: 0.5^2 + 2^2/4 + 2^2/16; flow: (2 % of 400)^2 + 8^2/4 + 8^2/16.
        self.assertEqual(v["heap_cone_angle_deg"], [(0.5, 0.25 + 1.0 + 0.25)])
        self.assertEqual(v["funnel_flow_rate_g_s"], [(8.0, 64.0 + 16.0 + 4.0)])


if __name__ == "__main__":
    unittest.main()
