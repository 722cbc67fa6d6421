"""How far the middle of a contact line slides, against the slip limit of its pairs.

At a case's resonance (its harmonic-1 peak) :func:`centre_slide` takes the
harmonic-1 amplitude of the tangential relative displacement of every pair,
``u_t = sqrt(|u_c|^2 + |u_s|^2)`` over both tangential directions (cos and
sin parts), averages it over the :data:`CENTRAL_PAIRS` central pairs of each
of the two lines, and compares it with ``mu N0 / kt``: the relative
displacement at which a pair held stuck by its spring ``kt`` reaches the
slip limit ``mu N0`` at its preload. A ratio above 1 means a pair held
stuck would need more than ``mu N0`` of tangential force: it slips unless
its normal load rises enough with the slide. That normal swing is given
too, ``kn u_n / N0`` (the harmonic-1 normal amplitude ``u_n``) at the
centre and at the :data:`END_PAIRS` pairs at each end: the rocking that
unloads the ends. This is the measurement behind the cone's status
maps (docs/notes/energy_convergence.md, "Item 4: why the cone's line
centres slip"), computed from the case record alone:

- the relative displacements are the solved unknowns ``branch.x`` when the
  balance was condensed onto every contact DOF (the unknowns are then the
  harmonics of ``(t1, t2, n)`` of each pair, in the layout of
  :mod:`workbench.hbm.core.fourier`);
- the slip limit comes from the case's inputs (:mod:`.provenance`): each
  pair's preload and stiffness are both proportional to its weight (its
  length on the line, ``assembly/model.py`` ``preloads`` and
  ``assembly/params.py`` ``pair_stiffness``), so ``mu N0 / kt`` is the same
  for every pair of a side: ``mu`` times the side's preload over the side's
  stiffness, which is half of ``kt_total`` when the two lines are alike.

A case without that data (no point, the physical space, other inputs)
gives None: the caller then says nothing numeric.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..hbm.core.fourier import Fourier
from .results import CaseResult

CENTRAL_PAIRS = 5  # the pairs averaged at the middle of each line (the note's definition)
END_PAIRS = 2  # the pairs averaged at each end of each line (the note's definition)


@dataclass(frozen=True)
class CentreSlide:
    """The slide at the middle of the contact lines at the resonance, and the slip limit."""

    slide_um: float  # harmonic-1 tangential amplitude, mean over the central pairs, um
    limit_um: float  # mu N0 / kt of a pair, um
    force_n: float
    peak_mm: float  # the harmonic-1 peak of the response, mm
    # the rocking: harmonic-1 swing of the normal load over the preload, kn u_n / N0, mean
    # over the central pairs and over the END_PAIRS at each end of each line (None: no kn)
    swing_centre: float | None = None
    swing_ends: float | None = None

    @property
    def ratio(self) -> float:
        """Slide over slip limit: above 1 the middle of the line slips at the peak."""
        return self.slide_um / self.limit_um


def _input(case: CaseResult, key: str) -> float | None:
    entry = case.inputs.get(key)
    if not isinstance(entry, dict):
        return None
    try:
        value = float(entry.get("value"))
    except (TypeError, ValueError):
        return None
    return value if np.isfinite(value) else None


def slip_limit_m(case: CaseResult) -> float | None:
    """``mu N0 / kt`` of a pair (m) from the case's inputs; None without them or when the
    two sides do not hold the same number of pairs (lines that may differ)."""
    mu, n_side, kt_total = (_input(case, k) for k in ("mu", "preload_per_side", "kt_total"))
    side = np.asarray(case.side)
    n0, n1 = int(np.sum(side == 0)), int(np.sum(side == 1))
    if None in (mu, n_side, kt_total) or n0 != n1 or n0 + n1 != side.size or kt_total <= 0:
        return None
    return mu * n_side / (0.5 * kt_total)


def normal_swing(case: CaseResult, un_m: np.ndarray) -> np.ndarray | None:
    """``kn u_n / N0`` of every pair for normal amplitudes ``un_m`` (m): the swing of its
    normal load over its preload (weights cancel as in :func:`slip_limit_m`)."""
    kn_total, n_side = _input(case, "kn_total"), _input(case, "preload_per_side")
    if kn_total is None or n_side is None or n_side <= 0 or slip_limit_m(case) is None:
        return None
    return 0.5 * kn_total * np.asarray(un_m) / n_side


def h1_motion_m(case: CaseResult, i: int) -> tuple[np.ndarray, np.ndarray] | None:
    """(tangential, normal): (n_pairs,) harmonic-1 amplitudes of each pair's relative
    displacement (m) at point ``i``, the tangential one over both directions; None when the
    branch did not keep the contact displacements."""
    b = case.branch
    n = int(np.asarray(case.side).size)
    harmonics = tuple(int(h) for h in b.harmonics)
    if b.space != "condensed" or 1 not in harmonics or n == 0 or not 0 <= i < b.n_points:
        return None
    fourier = Fourier(harmonics, int(b.nt))
    x = np.asarray(b.x)
    if x.ndim != 2 or x.shape[1] != fourier.nh * 3 * n:
        return None  # some contact direction was not an unknown: no displacement of every pair
    u = x[i].reshape(fourier.nh, n, 3)
    c = fourier.index(1, "c")
    h1 = u[c : c + 2]  # cos and sin parts of (t1, t2, n)
    return np.sqrt((h1[:, :, :2] ** 2).sum(axis=(0, 2))), np.sqrt((h1[:, :, 2] ** 2).sum(axis=0))


def centre_slide(case: CaseResult) -> CentreSlide | None:
    """The slide at the middle of both lines at the case's harmonic-1 peak (see the module)."""
    i = case.h1_peak_index
    limit = slip_limit_m(case)
    motion = h1_motion_m(case, i) if i >= 0 else None
    if limit is None or motion is None:
        return None
    ut, un = motion
    side = np.asarray(case.side)
    mid, ends = [], []
    for s in (0, 1):
        on = np.flatnonzero(side == s)  # in order along the line
        if on.size < max(CENTRAL_PAIRS, 2 * END_PAIRS):
            return None
        k = (on.size - CENTRAL_PAIRS) // 2
        mid.extend(on[k : k + CENTRAL_PAIRS])
        ends.extend(np.r_[on[:END_PAIRS], on[-END_PAIRS:]])
    swing = normal_swing(case, un)
    return CentreSlide(
        slide_um=float(np.mean(ut[mid])) * 1e6,
        limit_um=limit * 1e6,
        force_n=float(case.force_n),
        peak_mm=float(case.h1_mm[i]),
        swing_centre=None if swing is None else float(np.mean(swing[mid])),
        swing_ends=None if swing is None else float(np.mean(swing[ends])),
    )


def limit_crossing(slides: list[CentreSlide]) -> tuple[float, float] | None:
    """The two neighbouring forces (N) between which the centre's slide passes the slip
    limit (ratio below 1 at the first, at or above 1 at the second); None if it does not
    cross within the forces given."""
    s = sorted(slides, key=lambda v: v.force_n)
    for a, b in zip(s, s[1:], strict=False):
        if a.ratio < 1.0 <= b.ratio:
            return a.force_n, b.force_n
    return None
