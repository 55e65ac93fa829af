#!/usr/bin/env python3
"""Tests for tools/discovery/seed_correlation.py against hand arithmetic.

    python3 -m unittest discover -s tools/python -p 'test_*.py' -v
"""

from __future__ import annotations

import runpy
import unittest
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
correlations = runpy.run_path(str(REPO / "tools" / "discovery" / "seed_correlation.py"))["correlations"]


def compare_of(observable: str, runs: list[list[float]]) -> dict:
    return {"rows": [{"observable": observable, "simulated": r} for r in runs]}


class SeedCorrelation(unittest.TestCase):
    def test_a_common_shift_correlates_fully(self):
        # Each condition is the same three deviations around its own mean and scale.
        c = correlations(compare_of("flow", [[10, 12, 14], [100, 110, 120], [5, 5.5, 6]]))
        corr, pairs = c["flow"]
        self.assertEqual(pairs, 3)
        self.assertAlmostEqual(corr, 1.0, places=12)

    def test_opposite_deviations_anticorrelate(self):
        corr, pairs = correlations(compare_of("cone", [[1, 2, 3], [3, 2, 1]]))["cone"]
        self.assertEqual(pairs, 1)
        self.assertAlmostEqual(corr, -1.0, places=12)

    def test_a_worked_pair(self):
        # a = (0, 0, 3): mean 1, sd sqrt(3), z = (-1, -1, 2)/sqrt(3).
        # b = (0, 1, 2): mean 1, sd 1, z = (-1, 0, 1).
        # sum z_a z_b / (R - 1) = (1 + 0 + 2) / sqrt(3) / 2 = sqrt(3) / 2.
        corr, _ = correlations(compare_of("tray", [[0, 0, 3], [0, 1, 2]]))["tray"]
        self.assertAlmostEqual(corr, 3**0.5 / 2, places=12)

    def test_a_reading_without_scatter_shares_nothing(self):
        corr, _ = correlations(compare_of("residue", [[0, 0, 0], [0, 1, 2]]))["residue"]
        self.assertEqual(corr, 0.0)

    def test_too_few_replicates_or_conditions_are_left_out(self):
        self.assertEqual(correlations(compare_of("x", [[1, 2], [3, 4]])), {})
        self.assertEqual(correlations(compare_of("x", [[1, 2, 3]])), {})


if __name__ == "__main__":
    unittest.main()
