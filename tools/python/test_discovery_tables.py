#!/usr/bin/env python3
"""Tests for tools/discovery/tables.py, the discovery proof's tables.

    python3 -m unittest discover -s tools/python -p 'test_*.py' -v

A hidden-effect study's output is made up here with known numbers, so that the two ratios of
the error after the fit (to the data's noise and to the injected noise alone) and the
relative noise (a percentage of each measured value) are checked against hand arithmetic.
"""

from __future__ import annotations

import io
import json
import math
import runpy
import tempfile
import unittest
from contextlib import redirect_stdout
from pathlib import Path
from types import SimpleNamespace

REPO = Path(__file__).resolve().parents[2]


def load_tables():
    """tables.py's functions (it is a script, not a package)."""
    return SimpleNamespace(**runpy.run_path(str(REPO / "tools" / "discovery" / "tables.py")))


def write_study(out: Path, standard_error=(0.02, 0.004)):
    """A study with two readings at two moistures: the cone angle (absolute noise) and the
    flow rate (relative noise)."""
    rows = []
    for m, cone, flow in [(3, 35.0, 400.0), (12, 42.0, 300.0)]:
        rows.append({"observable": "heap_cone_angle_deg", "value": cone, "uncertainty": 1.0,
                     "conditions": {"moisture_pct": m}})
        rows.append({"observable": "funnel_flow_rate_g_s", "value": flow, "uncertainty": 10.0,
                     "conditions": {"moisture_pct": m}})
    # Each reading's sum of z^2 over its two rows, as `compare` writes it in `verdicts`.
    for stage, cone, flow, chi2 in [("1-compare", 3.0, 50.0, (20.0, 10.0)),
                                    ("4-compare", 0.6, 9.0, (2.0, 2.0))]:
        (out / stage).mkdir(parents=True)
        obs = {"heap_cone_angle_deg": {"rmse": cone}, "funnel_flow_rate_g_s": {"rmse": flow},
               "tray_mass_g": {"rmse": 0.0}, "funnel_residue_g": {"rmse": 0.0}}
        verdicts = [{"observable": o, "n": 2, "chi2": [c, None]}
                    for o, c in zip(["heap_cone_angle_deg", "funnel_flow_rate_g_s"], chi2)]
        (out / stage / "compare.json").write_text(
            json.dumps({"rows": rows, "observables": obs, "verdicts": verdicts}))
    (out / "2-diagnose").mkdir()
    cands = [{"name": "fines", "statistic": 40.0, "p_value": 1e-9, "strength": 0.16},
             {"name": "capillary", "statistic": 1.0, "p_value": 0.9, "strength": 0.01}]
    (out / "2-diagnose" / "diagnosis.json").write_text(json.dumps({"candidates": cands}))
    (out / "3-fit").mkdir()
    fit = {"parameters": [{"label": "soil-soil.rolling_friction"}, {"label": "candidate.fines"}],
           "estimate": [0.01, 0.152], "standard_error": list(standard_error), "chi2": 7.5, "dof": 6}
    (out / "3-fit" / "fit.json").write_text(json.dumps(fit))
    (out / "data.csv").write_text("test,observable,source\nrepose,x,synth: truth m.toml with fines=0.15; seed 1\n")


def tables_of_study(truth=None, **study) -> str:
    """tables.py's output for write_study's study (with a `5-truth/` of these observables'
    RMSEs if given), at noise 0.5 deg, 0.5 g, 2 % and 0.05 g."""
    t = load_tables()
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "hidden-fines"
        write_study(out, **study)
        if truth is not None:
            (out / "5-truth").mkdir()
            (out / "5-truth" / "compare.json").write_text(json.dumps({"observables": truth}))
        spec = {"heap_cone_angle_deg": "0.5", "funnel_flow_rate_g_s": "2%",
                "tray_mass_g": "0.5", "funnel_residue_g": "0.05"}
        buf = io.StringIO()
        with redirect_stdout(buf):
            t.hidden_tables([str(out)], spec)
        return buf.getvalue()


class Tables(unittest.TestCase):
    def test_relative_noise_is_a_share_of_the_value(self):
        t = load_tables()
        spec = {"funnel_flow_rate_g_s": "2%", "heap_cone_angle_deg": "0.5"}
        self.assertAlmostEqual(t.injected(spec, "funnel_flow_rate_g_s", -300.0), 6.0)
        self.assertEqual(t.injected(spec, "heap_cone_angle_deg", 40.0), 0.5)

    def test_the_default_noise_is_the_scripts(self):
        t = load_tables()
        setup = (REPO / "tools" / "discovery" / "setup.sh").read_text()
        self.assertIn("NOISE=${NOISE:-" + t.default_noise() + "}", setup)

    def test_one_study_gives_both_ratios(self):
        text = tables_of_study()
        # The fitted strength 0.152 against the hidden 0.15, 0.004 its standard error: z = 0.5.
        self.assertIn("| fines (0.15) | fines | 40.0 | 1e-09 | 0.1600 | capillary (0.9) | 0.1520 | 0.0040 | 0.50 | 7.5 / 6 |", text)
        # Cone: 0.6 against an RMS uncertainty of 1.0 and an injected 0.5.
        self.assertIn("3 -> 0.6 (0.60, 1.20)", text)
        # Flow: 9 against 10, and against 2 % of 400 and 300 g/s (8 and 6, RMS sqrt(50)).
        self.assertIn(f"50 -> 9 (0.90, {9 / math.sqrt(50):.2f})", text)
        self.assertIn(f"largest RMSE after: 0.90x the data's noise, {9 / math.sqrt(50):.2f}x the injected noise", text)
        self.assertNotIn("the truth itself", text)

    def test_a_strength_the_fit_did_not_determine_has_no_z(self):
        text = tables_of_study(standard_error=(0.02, None))
        self.assertIn("| capillary (0.9) | 0.1520 | - | - | 7.5 / 6 |", text)

    def test_the_truths_own_error_beside_the_fits(self):
        truth = {"heap_cone_angle_deg": {"rmse": 0.7}, "funnel_flow_rate_g_s": {"rmse": 5.0},
                 "tray_mass_g": {"rmse": 0.0}, "funnel_residue_g": {"rmse": 0.0}}
        text = tables_of_study(truth)
        # Cone: the fit's 0.6 and the truth's 0.7 against 0.5; flow: 9 and 5 against sqrt(50).
        self.assertIn(f"| fines | 1.20 (truth 1.40) | {9 / math.sqrt(50):.2f} (truth {5 / math.sqrt(50):.2f}) |", text)

    def test_the_data_chi2_over_all_rows_before_and_after(self):
        text = tables_of_study()
        # chi^2_4 survival in closed form: P(chi^2_4 > x) = exp(-x/2) (1 + x/2).
        before = math.exp(-15.0) * 16.0  # 20 + 10 over 4 rows
        after = math.exp(-2.0) * 3.0  # 2 + 2 over 4 rows
        self.assertIn(f"| fines | 30.0 on 4 (p = {before:.2g}) | 4.0 on 4 (p = {after:.2g}) | - |", text)


if __name__ == "__main__":
    unittest.main()
