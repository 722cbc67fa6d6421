"""What a path problem offers the engine (:func:`workbench.hbm.path.engine.follow`).

A problem follows a curve of solutions ``z(s)`` of ``R(z, s) = 0`` in one
parameter ``s`` (the frequency of a forced response, the log of the modal
amplitude of a backbone). The engine works in the problem's scaled
variables ``y`` (the unknowns with the parameter last, each of order one)
and a metric ``m`` (weights per entry of ``y``); the problem keeps its own
scaling and its own corrector, so that the arithmetic of every solve is the
problem's. A solve returns a :class:`Solution`; the problem turns a
converged one into a row of its record (:meth:`PathProblem.record`), and
says in its own words why the path stopped (:meth:`PathProblem.say`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np

from .rows import Rows


class Stop(Exception):
    """The path ends here: ``message`` says why, ``failed`` whether that is a failure,
    ``completed`` whether the requested range is covered all the same."""

    def __init__(self, message: str, failed: bool, completed: bool = False):
        super().__init__(message)
        self.failed, self.completed = failed, completed


class LostContact(Stop):
    """The damper has lost every contact at the point just solved (not recorded)."""


@dataclass
class Solution:
    """One corrector solve. ``y``: the scaled unknowns with the parameter last (None when
    not converged); ``param``: the parameter in the problem's units (the target of a
    solve at a fixed parameter); ``raw``: the problem's own form of the solution."""

    y: np.ndarray | None
    param: float
    converged: bool
    its: int
    reason: str
    raw: Any = None


class PathProblem(Protocol):
    """The hooks of one path problem (see :mod:`workbench.hbm.path.engine` for when each
    is called). ``start`` and ``end``: the parameter range, in the problem's units."""

    rows: Rows
    start: float
    end: float

    def first_point(self) -> Solution:
        """The first point, solved (raises :class:`Stop` when it cannot be)."""

    def metric(self) -> np.ndarray:
        """The weights of the arc-length metric on ``y`` (may change as points come)."""

    def first_direction(self, p: Solution, m: np.ndarray) -> np.ndarray:
        """The direction of the first step from the first point."""

    def tangent(self, p: Solution) -> np.ndarray:
        """The tangent of the curve at ``p`` (unnormalised, any orientation); only for
        ``predictor = "tangent"``."""

    def solve_plane(self, y0: np.ndarray, yp: np.ndarray, t: np.ndarray, m: np.ndarray):
        """Solve from ``y0`` on the plane through ``yp`` normal to ``t`` (metric ``m``)."""

    def solve_sphere(self, p: Solution, yp: np.ndarray, t: np.ndarray, m: np.ndarray, ds: float):
        """Solve from ``yp`` on the sphere of radius ``ds`` around ``p`` (metric ``m``);
        only for a rule with ``fallbacks``."""

    def solve_at(self, guess: Any, param: float) -> Solution:
        """Solve at a fixed parameter from ``guess`` (the problem's own form)."""

    def natural_step(self, p: Solution, prev: Solution | None, t: Any, ds: float) -> Solution:
        """The next point at a parameter ``ds`` ahead (the problem's predictor)."""

    def end_guess(self, p: Solution, q: Solution) -> Any:
        """The guess at ``end`` between ``p`` and ``q`` (which passed it)."""

    def change(self, p: Solution, q: Solution) -> float:
        """The largest relative change of the problem's watched outputs from p to q."""

    def refresh(self) -> None:
        """A fresh linearisation at the next solve."""

    def record(self, p: Solution, at_end: bool = False) -> None:
        """Append ``p`` to ``rows`` (may raise :class:`LostContact` or :class:`Stop`)."""

    def record_past_end(self, p: Solution, q: Solution) -> None:
        """Record ``q`` (past ``end``) where the point at ``end`` failed; only for
        ``end = "once"``."""

    def after_point(self) -> None:
        """Called after each point of the loop is recorded (may raise :class:`Stop`)."""

    def say(self, what: str, **ctx: Any) -> str:
        """The problem's words for a stop of kind ``what`` (see the engine)."""
