"""Richardson extrapolation with the observed order: a converged value from a ladder of levels.

A discretisation knob (mesh size, modes, harmonics, AFT samples, contact
points per line) is described by a *fineness* ``h`` per level, smaller is
finer (mesh size in mm; ``1/modes``; ``1/H`` for the highest harmonic H;
``1/nt``; ``1/points``). In the asymptotic range a quantity behaves like

    q(h) = q0 + C h^p (+ higher-order terms),

and three levels h1 < h2 < h3 (any ratios) fix the three unknowns. The
order ``p`` is the root of

    (h3^p - h2^p) / (h2^p - h1^p) = (q3 - q2) / (q2 - q1),

solved by bisection (the left side grows monotonically with p), then
``C = (q2 - q1) / (h2^p - h1^p)`` and ``q0 = q1 - C h1^p``. Only the
finest three levels are used; coarser ones are often outside the
asymptotic range.

The estimate is flagged ``asymptotic = False`` (and NOT extrapolated: the
value is the finest level's, ``method = "finest level"``) when

* fewer than three finite values are given;
* the differences change sign (oscillating, non-monotone data): no power
  law fits them;
* the observed order lies outside ``p_range`` (default 0.5..8): too slow
  a convergence means the levels are pre-asymptotic, too fast means the
  differences are dominated by noise or a lucky cancellation;
* the differences are at round-off (relative ``rtol_converged``): the
  ladder has converged, the finest value is the answer, and the
  uncertainty is the largest difference seen (``method = "bounded"``,
  trusted: nothing is closer to converged).

A ladder whose finest three levels differ by no more than the quantity's
own resolution (``noise``: what the measurement itself cannot tell apart,
e.g. a peak picked among computed points a step apart) has converged as far
as it can be seen: ``method = "bounded"``, the finest level +- ``SAFETY``
times the larger of the spread and the resolution, whatever the signs of
its differences. On an unstructured mesh the model itself has such a
resolution: re-meshing at a slightly different setting moves every value
by a scatter that no refinement removes, which the scatter of the global
mesh ladder about its best least-squares trend measures (:func:`fit_scatter`).
Given as ``scatter``, it bounds finest three levels that oscillate within
it; ``workbench/post/fidelity.py`` gives it to the knobs that re-mesh, and
widens any narrower band of theirs to it.

With three levels, two of the other cases still bound the limit (``method = "bounded"``, value
the finest level's, ``trusted`` True though ``asymptotic`` is False):
oscillating differences that do not grow (``|q2 - q1| <= |q3 - q2|``,
finest first), and an observed order above the plausible range (the
differences shrink faster than any power law would make them). The limit
then lies within the finest three levels' spread, and the uncertainty is
``SAFETY`` times that spread (the procedure for oscillatory convergence of
Celik et al., "Procedure for estimation and reporting of uncertainty due
to discretization in CFD applications", J. Fluids Eng. 2008, which takes
half the spread; this takes 1.25 times the whole of it). Growing
oscillations, no fitting power law and orders below the range stay
untrusted: the ladder may be diverging or pre-asymptotic, and nothing
bounds it.

A ladder of four or more levels that the three-level estimate cannot read
(no power law through the finest three, an oscillation, an order outside
the range: typically scatter of a few tenths of a percent on
unstructured meshes, which re-place the nodes at every size) is fitted by
least squares over all its levels instead (:func:`least_squares`, after
Eca and Hoekstra, "A procedure for the estimation of the numerical
uncertainty of CFD calculations based on grid refinement studies", J.
Comput. Phys. 2014): ``q0 + C h^p`` at the better of p = 1 and p = 2; the
uncertainty adds the fit's standard deviation, its miss at the finest
level and the distance between the two orders' limits to the correction,
and is tripled (scaled by the scatter) when the scatter exceeds the data's
mean step (``method = "least squares"``, trusted, not ``asymptotic``).
Levels whose best order is the range's lowest (slow convergence or none,
as a point load's log(1/h)) are not fitted.

A ladder of four or more levels whose finest three oscillate, whose
differences shrink as the levels get finer (the order ``p*`` of a
power law fitted to their magnitudes, ``|q_i+1 - q_i| ~ h^p*``, positive, and
the finest step no larger than the one before it) is
an oscillatory convergence: its limit is bounded by three times the data
range ``Delta_M`` (the largest difference between any two levels) around
the finest level (:func:`data_range`; ``method = "bounded"``, trusted). That
is the rule of Eca and Hoekstra's least-squares version of Roache's grid
convergence index for oscillatory convergence, which also takes the smaller
of that bound and a fit's uncertainty: the fit is kept where its
uncertainty is the smaller. Differences that grow (``p* <= 0``, an
oscillatory divergence) are bounded by nothing.

No library of this package is imported here (plain numpy).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import asdict, dataclass, replace

import numpy as np

P_RANGE = (0.5, 8.0)  # plausible observed orders (dimensionless)
SAFETY = 1.25  # Roache's factor of safety for a three-level study with an observed order


@dataclass(frozen=True)
class LimitEstimate:
    """The converged value of one quantity on one ladder, in the quantity's own units.

    ``value``: the extrapolated limit q0 (``method = "richardson"``) or the
    finest level's value (``method = "finest level"``, a fallback);
    ``uncertainty``: a band half-width around ``value`` (same units), None
    where nothing supports one; ``order``: the observed order p (None if
    not found); ``asymptotic``: True only where the extrapolation is
    trusted; ``reason``: why not, in words (empty when asymptotic);
    ``finest``: the finest level's value; ``n_levels``: the levels used.
    """

    value: float | None
    uncertainty: float | None
    order: float | None
    asymptotic: bool
    method: str
    reason: str
    finest: float | None
    n_levels: int

    @property
    def trusted(self) -> bool:
        """Extrapolated (``asymptotic``), fitted over four or more levels, or bounded (by
        the finest levels' spread, their resolution or an oscillation's data range)."""
        return self.asymptotic or self.method in ("bounded", "least squares")

    @property
    def corrects(self) -> bool:
        """Whether ``value`` is an estimate beyond the finest level (a correction to add)."""
        return self.method in ("richardson", "least squares")

    def as_dict(self) -> dict:
        return dict(asdict(self), trusted=self.trusted)

    def error_pct(self, q: float | None) -> float | None:
        """|q - value| / |value| in percent (None: nothing to compare)."""
        if q is None or self.value is None or not math.isfinite(q) or self.value == 0:
            return None
        return abs(q - self.value) / abs(self.value) * 100.0

    def uncertainty_pct(self) -> float | None:
        """The uncertainty relative to |value|, in percent (None: unknown)."""
        if self.uncertainty is None or self.value is None or self.value == 0:
            return None
        return abs(self.uncertainty) / abs(self.value) * 100.0


def _ratio(h: np.ndarray, p: float) -> float:
    """(h3^p - h2^p) / (h2^p - h1^p) with h scaled by h1 (h1 < h2 < h3)."""
    x = h / h[0]
    return float((x[2] ** p - x[1] ** p) / (x[1] ** p - 1.0))


def observed_order(h: Sequence[float], q: Sequence[float]) -> float | None:
    """The order p of q = q0 + C h^p through three points (h ascending: finest first).

    Returns None when the differences change sign or vanish, or when no p in
    1e-3..50 fits (the ratio of differences is outside what a power law can make).
    """
    h = np.asarray(h, dtype=float)
    q = np.asarray(q, dtype=float)
    e21, e32 = q[1] - q[0], q[2] - q[1]
    if e21 == 0 or e32 == 0 or np.sign(e21) != np.sign(e32):
        return None
    target = math.log(e32 / e21)
    lo, hi = 1e-3, 50.0
    f_lo = math.log(_ratio(h, lo)) - target
    f_hi = math.log(_ratio(h, hi)) - target
    if f_lo * f_hi > 0:
        return None
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        f_mid = math.log(_ratio(h, mid)) - target
        if f_mid == 0 or hi - lo < 1e-12:
            return mid
        if f_lo * f_mid < 0:
            hi = mid
        else:
            lo, f_lo = mid, f_mid
    return 0.5 * (lo + hi)


def _fit(h: np.ndarray, q: np.ndarray, p: float) -> tuple[float, float, float]:
    """Least squares q = q0 + c h^p at a fixed p: (q0, c, residual sum of squares)."""
    A = np.column_stack([np.ones_like(h), h**p])
    (q0, c), *_ = np.linalg.lstsq(A, q, rcond=None)
    r = q - A @ np.array([q0, c])
    return float(q0), float(c), float(r @ r)


def _levels(h: Sequence[float], q: Sequence[float]) -> tuple[np.ndarray, np.ndarray]:
    """The levels as arrays (fineness, value), finest first."""
    pairs = sorted(zip((float(x) for x in h), (float(y) for y in q), strict=True))
    return np.array([a for a, _ in pairs]), np.array([b for _, b in pairs])


def _order_scan(x: np.ndarray, q: np.ndarray, p_range: tuple[float, float], n: int) -> list:
    """The residual sum of squares of ``q0 + c x^p`` at ``n`` orders log-spaced over
    ``p_range``, lowest first."""
    grid = np.exp(np.linspace(np.log(p_range[0]), np.log(p_range[1]), n))
    return [_fit(x, q, p)[2] for p in grid]


def _turns(d: np.ndarray) -> bool:
    """Whether the non-zero differences ``d`` change sign somewhere."""
    dn = d[d != 0.0]
    return bool(np.any(np.sign(dn[1:]) != np.sign(dn[:-1])))


def least_squares(
    h: Sequence[float],
    q: Sequence[float],
    *,
    p_range: tuple[float, float] = P_RANGE,
    safety: float = SAFETY,
    reason: str = "",
) -> LimitEstimate | None:
    """The limit of ``q`` fitted over all its levels (four or more; None with fewer, or
    when the levels do not converge).

    Four scattered levels cannot fix an order as well as a limit, so the order is
    not fitted: ``q0 + c h^p`` is fitted at p = 1 and at p = 2 (the orders that
    bracket the knobs here), and the better fit is kept. With ``eps = |q_finest - q0|``,
    ``sigma`` the fit's standard deviation, ``miss = |q_finest - fit(h_finest)|`` and
    ``spread`` the distance between the two fits' limits, the uncertainty is
    ``safety eps + sigma + miss + spread`` where the scatter is below the data's mean
    step ``Delta = (max q - min q) / (n - 1)``, else ``3 sigma / Delta`` times the same
    sum (after Eca and Hoekstra 2014, who also fall back on fixed orders). A ladder
    whose best free order (scanned over ``p_range``) is its lowest converges too slowly
    or not at all (a point load's log(1/h)): None. ``reason``: why the three-level
    estimate did not do.
    """
    hh, qq = _levels(h, q)
    n = len(hh)
    if n < 4:
        return None
    x = hh / hh[0]  # fineness relative to the finest level: well-scaled powers
    if int(np.argmin(_order_scan(x, qq, p_range, 200))) == 0:
        return None  # the data want an order at or below the range: no convergence to fit
    delta = float(qq.max() - qq.min()) / (n - 1)
    if delta == 0.0:
        return None
    fits = {p: _fit(x, qq, p) for p in (1.0, 2.0)}
    p = min(fits, key=lambda o: fits[o][2])
    q0, c, r2 = fits[p]
    sigma = math.sqrt(r2 / (n - 2))
    eps = abs(qq[0] - q0)
    miss = abs(qq[0] - (q0 + c))
    spread = abs(fits[1.0][0] - fits[2.0][0])
    total = eps + sigma + miss + spread
    unc = safety * eps + sigma + miss + spread if sigma < delta else 3.0 * sigma / delta * total
    why = (
        f"{reason}; fitted by least squares over {n} levels (order {p:g} of 1 and 2, "
        f"scatter {sigma:.3g} against a mean step {delta:.3g})"
    ).lstrip("; ")
    return LimitEstimate(float(q0), float(unc), p, False, "least squares", why, float(qq[0]), n)


def fit_scatter(h: Sequence[float], q: Sequence[float]) -> float | None:
    """The scatter of four or more levels about their trend: the standard deviation of
    the best least-squares fit ``q0 + c h^p``, its order scanned over ``P_RANGE`` (units
    of ``q``; three fitted parameters); None with fewer levels. A clean power law of any
    order in the range has (nearly) none: only what no trend explains counts."""
    hh, qq = _levels(h, q)
    if len(hh) < 4:
        return None
    return math.sqrt(min(_order_scan(hh / hh[0], qq, P_RANGE, 400)) / (len(hh) - 3))


def data_range(
    h: Sequence[float], q: Sequence[float], *, factor: float = 3.0
) -> LimitEstimate | None:
    """An oscillatory convergence bounded by ``factor`` times its data range (module doc).

    ``h``, ``q``: four or more levels (any order, distinct fineness). None unless the
    differences between consecutive levels change sign somewhere and their magnitudes
    shrink towards the finest level: a least-squares line through ``log |dq|`` against
    ``log h`` (h of each pair's geometric mean; zero differences left out, two or more
    needed) has a positive slope ``p*``, and the finest step is no larger than the one
    before it (the three-level rule's test of a growing oscillation). The value is the
    finest level's; no correction.
    """
    hh, qq = _levels(h, q)
    if len(hh) < 4:
        return None
    if len(set(hh.tolist())) != len(hh) or hh[0] <= 0:
        raise ValueError(f"fineness must be positive and distinct: {list(h)}")
    d = np.diff(qq)
    nz = d != 0.0
    dn = d[nz]
    if not _turns(d):
        return None  # monotone (or fewer than two steps): a fit or nothing, never this bound
    hm = np.sqrt(hh[1:] * hh[:-1])[nz]
    p_star = float(np.polyfit(np.log(hm), np.log(np.abs(dn)), 1)[0])
    if not p_star > 0.0:
        return None  # the oscillation grows as the levels get finer: nothing bounds it
    if abs(dn[0]) > abs(dn[1]):
        return None  # ... or its finest step outgrows the one before (as three levels judge)
    span = float(qq.max() - qq.min())
    why = (
        f"oscillating over {len(qq)} levels with differences that shrink (order of the "
        f"differences {p_star:.3g}); bounded by {factor:g} times the data range {span:.3g}"
    )
    return LimitEstimate(float(qq[0]), factor * span, None, False, "bounded", why, float(qq[0]),
                         len(qq))  # fmt: skip


def richardson(
    h: Sequence[float],
    q: Sequence[float | None],
    *,
    p_range: tuple[float, float] = P_RANGE,
    safety: float = SAFETY,
    rtol_converged: float = 1e-9,
    noise: float | None = None,
    scatter: float | None = None,
) -> LimitEstimate:
    """The converged value of ``q`` from its finest three levels, with the observed order.

    ``h``: fineness of each level (any unit, smaller is finer; any order,
    distinct); ``q``: the quantity at each level (None or NaN: a failed
    level, dropped). The uncertainty is Roache's grid convergence index in
    the quantity's units, ``U = safety * |q_finest - q0|`` with
    ``safety = 1.25``: the extrapolation's own correction, widened by a
    quarter because the observed order is itself estimated from the same
    three points (for data that follow a power law plus a higher-order
    term the true limit falls inside U; the tests check it). The
    difference between the three-level and a two-level extrapolation is
    not used: with the observed order the two coincide by construction.
    ``noise``: the quantity's resolution in its units (None or 0: none known); a ladder
    whose finest three levels lie within it is bounded by it (module doc). ``scatter``:
    the model's re-meshing scatter (None: none); finest three levels that oscillate
    within it are bounded by it (x ``safety``), as they are by a resolution; a monotone
    trend is read as usual.
    """
    pairs = sorted(
        (float(hh), float(qq))
        for hh, qq in zip(h, q, strict=True)
        if qq is not None and math.isfinite(float(qq))
    )
    hs = [p[0] for p in pairs]
    if len(set(hs)) != len(hs) or any(x <= 0 for x in hs):
        raise ValueError(f"fineness must be positive and distinct: {list(h)}")
    n = len(pairs)
    finest = pairs[0][1] if pairs else None

    def fallback(reason: str, order: float | None = None, unc: float | None = None):
        return LimitEstimate(finest, unc, order, False, "finest level", reason, finest, n)

    def unread(reason: str, order: float | None = None, oscillating: bool = False):
        """The finest three levels cannot be read: all of them fitted, if four or more;
        an oscillation of the finest three also bounded by its data range."""
        hs_, qs_ = [a for a, _ in pairs], [b for _, b in pairs]
        fit = least_squares(hs_, qs_, p_range=p_range, safety=safety, reason=reason)
        rng = data_range(hs_, qs_) if oscillating else None
        if rng is not None and (fit is None or rng.uncertainty < fit.uncertainty):
            return replace(rng, reason=f"{reason}; {rng.reason}")
        if fit is not None:
            return fit
        if n >= 4:  # say why the levels beyond the finest three did not help either
            reason += f"; over all {n} levels no converging order fits" + (
                " and the oscillation does not shrink towards the finest"
                if _turns(np.diff(qs_))
                else ""
            )
        return fallback(reason, order)

    if n < 3:
        return fallback(f"{n} level(s) with a value: three are needed for an observed order")
    hh = np.array(hs[:3])
    qq = np.array([p[1] for p in pairs[:3]])
    e21, e32 = qq[1] - qq[0], qq[2] - qq[1]
    scale = max(abs(qq).max(), np.finfo(float).tiny)
    if max(abs(e21), abs(e32)) <= rtol_converged * scale:
        why = f"converged to round-off: the finest levels agree within {rtol_converged:g}"
        return LimitEstimate(
            finest, float(max(abs(e21), abs(e32))), None, False, "bounded", why, finest, 3
        )
    spread = float(qq.max() - qq.min())

    def bounded(reason: str, order: float | None = None) -> LimitEstimate:
        why = f"{reason}; bounded by the finest three levels' spread (x {safety:g})"
        return LimitEstimate(finest, safety * spread, order, False, "bounded", why, finest, 3)

    if noise and spread <= noise:
        why = (
            f"the finest three levels differ by {spread:.3g}, within the quantity's "
            f"resolution {noise:.3g}; bounded by it (x {safety:g})"
        )
        return LimitEstimate(finest, safety * noise, None, False, "bounded", why, finest, 3)

    if e21 == 0 or e32 == 0 or np.sign(e21) != np.sign(e32):
        why = "oscillating: the differences between the finest levels change sign"
        if scatter and spread <= scatter:
            why += (
                f", by {spread:.3g}, within the re-meshing scatter {scatter:.3g}; bounded by "
                f"it (x {safety:g})"
            )
            return LimitEstimate(finest, safety * scatter, None, False, "bounded", why, finest, 3)
        if n >= 4:
            return unread(why, oscillating=True)
        if abs(e21) <= abs(e32):
            return bounded(why)
        return unread(why + ", and grow as the levels get finer")
    p = observed_order(hh, qq)
    if p is None:
        return unread("no power law fits the finest three levels")
    if p > p_range[1]:
        why = (
            f"observed order {p:.3g} above the plausible {p_range[1]:g}: the differences "
            "shrink faster than a power law"
        )
        return unread(why, order=p) if n >= 4 else bounded(why, order=p)
    if p < p_range[0]:
        return unread(
            f"observed order {p:.3g} outside the plausible {p_range[0]:g}..{p_range[1]:g}: "
            "the levels are not in the asymptotic range",
            order=p,
        )
    c = e21 / (hh[1] ** p - hh[0] ** p)
    q0 = float(qq[0] - c * hh[0] ** p)
    unc = float(safety * abs(qq[0] - q0))
    return LimitEstimate(q0, unc, float(p), True, "richardson", "", finest, 3)


__all__ = [
    "P_RANGE",
    "SAFETY",
    "LimitEstimate",
    "data_range",
    "fit_scatter",
    "least_squares",
    "observed_order",
    "richardson",
]
