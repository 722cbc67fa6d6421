"""Small helpers shared by the rig layout and the damper shapes (pure numpy, mm).

Fit errors that name the parameter to change, the check that a step
between two faces is either absent or at least the smallest feature, the
CAD kernel's "same face" distance and the tributary length of points along
a line.
"""

from __future__ import annotations

import numpy as np

from ..errors import InputError

# Two faces closer than this are the same face to the CAD kernel (its
# tolerance is 1e-7 mm): a step below it is "no step".
SAME_MM = 1e-6


def fit_error(param: str, value: float, allowed: str, why: str) -> InputError:
    """The error of a damper or rig that does not fit, naming the parameter to change."""
    return InputError(param, value, allowed, why)


def check_step(param: str, value: float, step: float, f: float, what: str) -> None:
    """A step between faces is absent (below SAME_MM) or at least ``f``; else InputError."""
    if SAME_MM <= abs(step) < f:
        raise fit_error(
            param,
            value,
            f"a value that leaves no step or a step of at least rig.fit.min_feature_mm = {f:g} mm",
            f"{what} would be {abs(step):.3g} mm",
        )


def voronoi_1d(x: np.ndarray, lo: float, hi: float) -> np.ndarray:
    """Length of each sorted point's nearest-point cell within [lo, hi]."""
    mids = 0.5 * (x[1:] + x[:-1])
    edges = np.concatenate([[lo], mids, [hi]])
    return np.diff(edges)
