"""The path engine on its own: a toy problem with two folds, followed by arc length.

The curve ``z^3 - z = s`` turns back in ``s`` at ``z = -1/sqrt(3)`` and again at
``z = 1/sqrt(3)``. From ``z = -1.5`` (``s = -1.875``) to ``s = 1.875`` the
arc-length loop must pass both folds and end exactly at ``s = 1.875`` on the
outer branch (``z = 1.5``); natural steps in ``s`` cannot pass a fold. The
toy adapter is also the smallest example of a path problem
(docs/DEVELOPING.md, "How to add a path problem").
"""

from __future__ import annotations

import numpy as np
import pytest

from workbench.hbm.path.engine import follow, norm
from workbench.hbm.path.problem import LostContact, Solution
from workbench.hbm.path.rows import Rows
from workbench.hbm.path.step import StepRule

FOLD = 1 / np.sqrt(3)
S_FOLD = FOLD - FOLD**3  # s at the first fold (z = -FOLD)


class Cubic:
    """``R(z, s) = z^3 - z - s``, unknowns ``y = (z, s)``, plain Newton in numpy."""

    def __init__(self, s0=-1.875, s1=1.875, lost_above=None):
        self.start, self.end = s0, s1
        self.rows = Rows(("z", "s", "its"))
        self.lost_above = lost_above  # a "lost contact" past this z (for the stop rule)

    def _newton(self, y, extra, jac_extra):
        for its in range(1, 30):
            z, s = y
            F = np.array([z**3 - z - s, extra(y)])
            if np.abs(F).max() < 1e-13:
                return Solution(y.copy(), float(y[1]), True, its, "", y[0])
            J = np.array([[3 * z**2 - 1, -1.0], jac_extra])
            y = y - np.linalg.solve(J, F)
        return Solution(y, float(y[1]), False, its, "max_it", y[0])

    def first_point(self):
        z = -1.5
        p = Solution(np.array([z, self.start]), self.start, True, 0, "", z)
        self.record(p)
        return p

    def metric(self):
        return np.ones(2)

    def tangent(self, p):
        return np.array([1.0, 3 * p.y[0] ** 2 - 1])

    def first_direction(self, p, m):
        t = self.tangent(p)
        return t / norm(t, m)

    def solve_plane(self, y0, yp, t, m):
        c = m * m * t
        return self._newton(y0, lambda y: c @ (y - yp), c)

    def solve_at(self, guess, param):
        return self._newton(np.array([guess, param]), lambda y: y[1] - param, np.array([0, 1.0]))

    def natural_step(self, p, prev, t, ds):
        return self.solve_at(p.raw, min(p.param + ds, self.end))

    def end_guess(self, p, q):
        return p.raw + (self.end - p.param) / (q.param - p.param) * (q.raw - p.raw)

    def change(self, p, q):
        return 0.0

    def refresh(self):
        pass

    def record(self, p, at_end=False):
        if self.lost_above is not None and p.raw > self.lost_above:
            raise LostContact(f"lost at z = {p.raw:.3f}", failed=False)
        self.rows.add(z=float(p.raw), s=float(p.param), its=p.its)

    def after_point(self):
        pass

    def say(self, what, **ctx):
        return f"stop: {what}"


ARC = StepRule(mode="arclength", ds0=0.05, ds_min=1e-5, ds_max=0.2, max_points=2000)


def test_arclength_passes_both_folds_and_ends_on_the_end():
    pb = Cubic()
    out = follow(pb, ARC)
    assert (out.completed, out.failed, out.message) == (True, False, "")
    z, s = np.array(pb.rows.cols["z"]), np.array(pb.rows.cols["s"])
    np.testing.assert_allclose(z**3 - z, s, atol=1e-12)  # every point on the curve
    assert np.all(np.diff(z) > 0)  # along the curve, never back
    ds = np.diff(s)
    assert np.any(ds < 0) and ds[0] > 0 and ds[-1] > 0  # through the middle piece backwards
    assert z.min() < -FOLD and np.any(np.abs(z) < 0.1) and z.max() > FOLD  # both folds
    assert s[-1] == 1.875 and z[-1] == pytest.approx(1.5, abs=1e-12)


def test_natural_steps_stop_at_the_fold():
    """The same curve by steps in s cannot pass the first fold: the steps shrink to the
    smallest one just below it and the path ends failed, with the points up to it."""
    pb = Cubic()
    rule = StepRule(
        mode="natural", ds0=0.05, ds_min=1e-3, ds_max=0.05, end="clip", target_newton=10
    )
    out = follow(pb, rule)
    assert (out.completed, out.failed, out.message) == (False, True, "stop: failed")
    s = np.array(pb.rows.cols["s"])
    assert np.all(np.diff(s) > 0) and 0 < S_FOLD - s[-1] < 2e-3


def test_a_lost_contact_ends_the_path_and_keeps_the_points():
    pb = Cubic(lost_above=0.9)
    out = follow(pb, ARC)
    assert not out.completed and not out.failed and out.message.startswith("lost at z = ")
    z = pb.rows.cols["z"]
    assert max(z) <= 0.9 < float(out.message.split("= ")[1]) and len(z) > 10


def test_the_point_budget_stops_the_path():
    pb = Cubic()
    out = follow(pb, StepRule(**{**ARC.__dict__, "max_points": 5}))
    assert (out.completed, out.failed, out.message) == (False, False, "stop: max_points")
    assert pb.rows.n == 5
