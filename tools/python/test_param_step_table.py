#!/usr/bin/env python3
"""Tests for tools/discovery/param_step_table.py, the table of the free parameters' step in
`diagnose`: a proof directory is made up with known diagnoses, and the counts and means are
checked against hand arithmetic.

    python3 -m unittest discover -s tools/python -p 'test_*.py' -v
"""

from __future__ import annotations

import json
import runpy
import tempfile
import unittest
from pathlib import Path
from types import SimpleNamespace

REPO = Path(__file__).resolve().parents[2]
HIDDEN = ["fines", "wall_adhesion", "plastic_adhesion"]


def load():
    return SimpleNamespace(**runpy.run_path(str(REPO / "tools" / "discovery" / "param_step_table.py")))


def write(d: Path, ranking: list[tuple[str, bool, float]], shift: float, measurable: bool) -> None:
    """A diagnosis.json: candidates best first as (name, significant, strength)."""
    d.mkdir(parents=True)
    doc = {
        "candidates": [
            {"name": n, "significant": s, "strength": v} for n, s, v in ranking
        ],
        "recalibration": [{"shift": shift, "measurable": measurable}],
    }
    (d / "diagnosis.json").write_text(json.dumps(doc))


class ParamStepTable(unittest.TestCase):
    def test_counts_and_means(self):
        t = load()
        with tempfile.TemporaryDirectory() as tmp:
            proof = Path(tmp)
            for e in HIDDEN:
                others = [(o, False, 0.0) for o in HIDDEN if o != e]
                # Draw 1: the hidden effect first and significant; draw 2: first but not
                # significant (fines), or another candidate first (the two adhesions).
                write(proof / f"rate-{e}/seed1/sub", [(e, True, 0.3)] + others, 0.1, True)
                if e == "fines":
                    second = [(e, False, 0.1)] + others
                else:
                    second = [others[0], (e, True, 0.1), others[1]]
                write(proof / f"rate-{e}/seed2/sub", second, -0.3, False)
            # Null seeds: one with a significant candidate, two without.
            for s, sig in [(1, True), (2, False), (3, False)]:
                write(proof / f"null/seed-{s}/sub", [("fines", sig, 0.0)], 0.0, True)
            row = t.row(proof, "sub")
            for e in HIDDEN:
                hits, draws, shift, strength = row["effects"][e]
                self.assertEqual((hits, draws), (1, 2), e)
                self.assertAlmostEqual(shift, -0.1)
                self.assertAlmostEqual(strength, 0.2)
            self.assertEqual(row["alarms"], (1, 3))
            self.assertEqual(row["measurable"], (3, 6))
            text = t.table(proof, [("sub", "9 %")])
            self.assertIn("| 9 % | 1/2 / 1/2 / 1/2 | 1/3 | 3/6 | -0.100 / -0.100 / -0.100 | "
                          "0.2000 / 0.2000 / 0.2000 |", text)

    def test_the_proofs_own_diagnoses_are_read_from_both_names(self):
        t = load()
        with tempfile.TemporaryDirectory() as tmp:
            case = Path(tmp)
            write(case / "diagnose", [("fines", True, 0.1)], 0.0, True)
            self.assertEqual(t.diagnosis(case, "2-diagnose")["candidates"][0]["name"], "fines")


if __name__ == "__main__":
    unittest.main()
