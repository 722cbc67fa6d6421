"""Work per cycle of the contact forces on their sampled loops (trapezoid rule).

``u``, ``f`` (n_el, nt, 3): displacement and force samples of one period of
each contact element (tangential 1, 2 and normal), from the AFT. The
tangential work is the friction dissipation reported per element; the
normal work is zero for a resolved loop (the unilateral spring is
conservative).
"""

from __future__ import annotations

import numpy as np


def loop_normal_work(u: np.ndarray, f: np.ndarray) -> np.ndarray:
    """(n_el,) work per cycle (J) of the normal force on its loop, trapezoid rule.

    The unilateral spring is conservative: zero for a resolved loop; where the
    contact opens between samples the trapezoid misses the kink.
    """
    du = np.roll(u[:, :, 2], -1, axis=1) - u[:, :, 2]
    favg = 0.5 * (f[:, :, 2] + np.roll(f[:, :, 2], -1, axis=1))
    return np.einsum("et,et->e", favg, du)


def loop_dissipation(u: np.ndarray, f: np.ndarray) -> np.ndarray:
    """(n_el,) energy per cycle (J) of the tangential forces on their converged loops.

    ``u``, ``f`` (n_el, nt, 3): displacement and force samples of one period
    (the period closes: sample nt is sample 0). Trapezoid rule on the loop.
    """
    du = np.roll(u[:, :, :2], -1, axis=1) - u[:, :, :2]
    favg = 0.5 * (f[:, :, :2] + np.roll(f[:, :, :2], -1, axis=1))
    return np.einsum("etk,etk->e", favg, du)
