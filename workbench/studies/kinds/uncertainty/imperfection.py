"""A seating imperfection of the damper as a tilted preload along one side's contact.

A drawing's damper sits on both platforms along its whole line (cone,
cylinder) or face (wedge), and the assembly shares each side's normal
force uniformly (per unit of line or face: ``workbench.assembly.model``).
A real seat is misaligned by a small angle ``delta`` (a platform angle
mismatch, a cone seat ground at a slightly wrong angle, a wedge face angle
mismatch): along the side's longest extent ``s`` the surfaces then start
with a gap ``g(s) = tan|delta| (s - s_end)`` that grows from the end that
touches first. Seated by its centrifugal load, the (locally rigid) damper
approaches the platform by ``d``; pair ``i`` is pressed by

    n0_i = kn_i max(0, d - g_i),      sum over the side of n0_i = N_side

(``N_side``, the side's normal force from the static balance, does not
change). ``delta = 0`` gives back the uniform preload exactly. When
``tan|delta| L`` exceeds the static approach ``N_side / kn_side`` the
pairs at the far end carry no preload: the line contact opens at one end.

Assumptions (stated in docs/STUDIES.md): only side 0 is misaligned (the
other side keeps the drawing's seat); the damper does not rotate to
accommodate the tilt (the other side holds it); a pair whose initial gap
exceeds the approach is modelled as touching with zero preload (the
contact law has no initial gap: it opens under any pull and closes under
any push), which overstates the contact at the open end for vibration
amplitudes below the gap. The sign of ``delta`` chooses the end that opens.

Only the preload vector changes: the mesh, the reduced models and the
coupling matrix ``W`` are shared with the perfect seat. This module is
part of every uncertainty sample's cache key (its source is hashed).
"""

from __future__ import annotations

import math

import numpy as np


def side_coordinate(points: np.ndarray) -> np.ndarray:
    """Coordinate (m) of each point along the points' longest extent (principal axis).

    The axis' sign is fixed (its largest component positive) so the
    coordinate does not depend on the SVD's arbitrary sign.
    """
    p = np.asarray(points, dtype=float)
    if len(p) < 2:
        return np.zeros(len(p))
    c = p - p.mean(axis=0)
    _, _, vt = np.linalg.svd(c, full_matrices=False)
    e = vt[0]
    if e[np.argmax(np.abs(e))] < 0:
        e = -e
    return c @ e


def seated_preloads(kn: np.ndarray, gap: np.ndarray, total: float) -> np.ndarray:
    """``n0_i = kn_i max(0, d - g_i)`` with ``d`` such that ``sum n0 = total`` (N).

    Exact: the sum is piecewise linear and increasing in ``d``; the pairs
    are closed in order of increasing gap.
    """
    kn = np.asarray(kn, dtype=float)
    g = np.asarray(gap, dtype=float)
    if total <= 0.0:
        return np.zeros_like(kn)
    order = np.argsort(g, kind="stable")
    gs, ks = g[order], kn[order]
    ck = np.cumsum(ks)
    ckg = np.cumsum(ks * gs)
    d = gs[-1]
    for m in range(len(gs)):  # pairs 0..m closed: d = (total + sum k g) / sum k
        d_m = (total + ckg[m]) / ck[m]
        if m + 1 == len(gs) or d_m <= gs[m + 1]:
            d = d_m
            break
    return kn * np.maximum(0.0, d - g)


def tilted_preloads(
    points: np.ndarray,
    side: np.ndarray,
    kn: np.ndarray,
    n0: np.ndarray,
    tilt_deg: float,
    tilted_side: int = 0,
) -> np.ndarray:
    """The uniform preloads ``n0`` (N) redistributed on ``tilted_side`` by a seat tilt (deg)."""
    out = np.array(n0, dtype=float, copy=True)
    if tilt_deg == 0.0:
        return out
    on = np.asarray(side) == tilted_side
    s = side_coordinate(np.asarray(points)[on])
    t = math.tan(math.radians(abs(tilt_deg)))
    gap = t * (s - s.min()) if tilt_deg > 0 else t * (s.max() - s)
    out[on] = seated_preloads(np.asarray(kn)[on], gap, float(np.sum(out[on])))
    return out


def open_share(n0: np.ndarray, side: np.ndarray, tilted_side: int = 0) -> float:
    """Share of the tilted side's pairs that carry no preload (opened at rest)."""
    on = np.asarray(side) == tilted_side
    return float(np.mean(np.asarray(n0)[on] <= 0.0)) if on.any() else 0.0
