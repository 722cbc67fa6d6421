"""The mistuning patterns: one frequency deviation per blade, sampled, and their stiffness.

A pattern is a vector of ``N`` blade frequency deviations ``df_j`` (fractions
of the tuned blade's frequency). They are drawn as standard normal deviates
``z`` from a design on the unit cube ``[0, 1)^N`` (``scipy.stats.qmc``:
a scrambled Sobol sequence or a Latin hypercube, seeded) through the normal
inverse CDF, scaled by the standard deviation ``s``: ``df = s z``. A blade's
frequency goes as the square root of its stiffness, so its stiffness
deviation is ``delta_j = (1 + df_j)^2 - 1`` (the blade's stiffness scaled by
``(1 + df_j)^2``). A deviate with ``1 + df_j <= 0`` has no blade behind it:
such a pattern is refused (``mistuning-std`` too large for the draw).

The Sobol design of ``n`` patterns is the first ``n`` points of the
sequence drawn to the next power of 2, so a larger count keeps every
pattern of a smaller one (and their cached solutions); a Latin hypercube
depends on its count.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ....errors import InputError, check_choice, check_int, check_range


@dataclass(frozen=True)
class Patterns:
    """The sampled patterns: ``z`` standard normal deviates, ``df`` frequency deviations
    and ``delta`` stiffness deviations, each (patterns, blades)."""

    z: np.ndarray
    df: np.ndarray
    delta: np.ndarray
    std_percent: float
    sampling: str
    seed: int

    @property
    def n_patterns(self) -> int:
        return int(self.z.shape[0])

    @property
    def n_blades(self) -> int:
        return int(self.z.shape[1])


def unit_design(n: int, d: int, sampling: str, seed: int) -> np.ndarray:
    """``n`` points of the ``d``-dimensional design ``sampling`` ("sobol" or "lhs") on the
    open unit cube."""
    from scipy.stats import qmc

    sampling = check_choice("mistuning-sampling", sampling, ("sobol", "lhs"))
    if sampling == "sobol":
        m = max(0, math.ceil(math.log2(n)))
        u = qmc.Sobol(d, scramble=True, seed=seed).random_base2(m)[:n]
    else:
        u = qmc.LatinHypercube(d, seed=seed).random(n)
    return np.clip(u, 1e-12, 1.0 - 1e-12)  # the inverse CDF is finite


def sample_patterns(
    n_patterns: int, n_blades: int, std_percent: float, sampling: str = "sobol", seed: int = 0
) -> Patterns:
    """``n_patterns`` patterns of ``n_blades`` blades with frequency standard deviation
    ``std_percent`` (percent); InputError naming the option for a bad value or a draw that
    leaves a blade without a positive frequency."""
    from scipy.stats import norm

    n = check_int("mistuning-patterns", n_patterns, 2, 100000)
    d = check_int("n-blades", n_blades, 2)
    s = check_range("mistuning-std", std_percent, 0.0, 50.0, unit="%") / 100.0
    z = norm.ppf(unit_design(n, d, sampling, int(seed)))
    df = s * z
    bad = np.argwhere(1.0 + df <= 0.0)
    if len(bad):
        p, j = (int(v) for v in bad[0])
        limit = 100.0 / float(-z.min())
        raise InputError(
            "mistuning-std",
            std_percent,
            f"0 <= mistuning-std < {limit:.3g} % for these {n} patterns (seed {seed})",
            f"pattern {p + 1} blade {j + 1} draws a frequency factor 1 + df = {1 + df[p, j]:.3g}"
            " <= 0: no positive blade stiffness (1 + df)^2 behind it",
        )
    return Patterns(z, df, (1.0 + df) ** 2 - 1.0, s * 100.0, sampling, int(seed))


def study_patterns(spec: Any) -> Patterns:
    """The patterns of a mistuning study ``spec`` (its ``n-blades`` and ``mistuning-*``)."""
    o = spec.mistuning
    return sample_patterns(
        o.mistuning_patterns,
        spec.bladed_disk.n_blades,
        o.mistuning_std,
        o.mistuning_sampling,
        o.mistuning_seed,
    )
