"""Forced responses from one nonlinear mode (single-nonlinear-mode theory, Krack 2015).

Near an isolated resonance the forced motion at excitation frequency
``W`` is taken as the nonlinear mode at some modal amplitude ``a``,
``q(t) ~ a Re(psi(a) exp(i (W t + theta)))`` (all its harmonics), and the
projection of the equation of motion on the harmonic-1 shape gives

    a^2 [ (w(a)^2 - W^2)^2 + (xi(a) w(a) + c(a) (W - w(a)))^2 ] = |psi_1(a)^H f1|^2 level^2

with ``w``, ``xi`` (``2 D w``), ``c = psi_1^H C psi_1`` (the viscous share
of ``xi``) and ``psi`` from the backbone (:class:`.record.NlModeBranch`).
The friction share ``xi - c`` is taken as rate independent (its work per
cycle depends on the amplitude only, as for Coulomb friction), the viscous
share as proportional to ``W``; Krack's original form ``xi W`` for the
whole term differs from this by ``O(D^2)`` at the peak. For each amplitude
of the backbone the two positive roots ``W`` of that quartic are the two
sides of the resonance; the peak is at the smallest amplitude where
``a min_W sqrt(...)`` reaches the modal force ``F``. Any force level
costs a few array operations.

Validity (checked automatically at the peak, :func:`synthesize`): the peak
amplitude lies on the computed backbone; the harmonic-1 shape there is
close to the low-amplitude one (mass-weighted MAC >= ``mac_min``: else the
contacts have redistributed the motion over other modes, which the single
mode cannot represent for another force distribution); no other linear
mode lies within ``separation`` of the frequency (modal interaction); the
higher harmonics stay below ``higher_max`` of the motion (an internal
resonance pumps energy into them); the damping ratio stays below
``damping_max`` (the theory assumes a light, resonant response); the
other modes' stuck linear response to the same force at the peak frequency
stays below ``others_max`` of the peak amplitude (what the single mode
leaves out: a close or strongly driven neighbour); the peak is not
interpolated over a backbone segment wider than ``SEGMENT_MAX`` in amplitude
across which the output per modal amplitude changes by more than
``SEGMENT_CHANGE`` (the continuation solves a point at each requested
level's peak; this catches a level it did not, or one where that solve failed).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ...errors import InputError, check_range
from .record import NlModeBranch

TWO_PI = 2.0 * np.pi
# a peak inside a backbone segment wider than this in amplitude, whose output per modal
# amplitude changes by more than SEGMENT_CHANGE across it, is not trusted to the interpolation
# (e.g. the one step across the stuck range, where a shakedown of the stuck contacts can
# shift the mean position)
SEGMENT_MAX = 1.25
SEGMENT_CHANGE = 0.02


@dataclass
class Synthesis:
    """A synthesised forced response at one level: the curve, its peak and its validity."""

    level: float
    freq_hz: np.ndarray  # the curve, increasing frequency along the left side then back
    out_amp: np.ndarray  # output amplitude along the curve (model length unit)
    peak_freq_hz: float
    peak_amplitude: float  # output amplitude at the peak
    peak_modal_amplitude: float
    valid: bool
    peak_h1: float = float("nan")  # harmonic-1 output amplitude at the peak
    reasons: list[str] = field(default_factory=list)
    checks: dict[str, float] = field(default_factory=dict)

    def summary(self) -> dict[str, Any]:
        return dict(
            level=self.level,
            peak_frequency_hz=self.peak_freq_hz,
            peak_amplitude=self.peak_amplitude,
            peak_modal_amplitude=self.peak_modal_amplitude,
            peak_h1=self.peak_h1,
            valid=self.valid,
            reasons=list(self.reasons),
            checks=dict(self.checks),
        )


FLANK_RATIO = 1.05  # the curve's largest amplitude step between backbone points


def _sides(w: float, xi: float, c: float, F: float, a: float) -> tuple[float, float]:
    """(left, right) excitation frequencies W (rad/s) at which the response has modal
    amplitude ``a``: the real roots W > 0 of
    W^4 + (c^2 - 2 w^2) W^2 + 2 c (xi - c) w W + w^4 + (xi - c)^2 w^2 - F^2 / a^2 = 0
    (nan where a side does not exist: above the peak both are nan)."""
    r = np.roots(
        [
            1.0,
            0.0,
            c**2 - 2 * w**2,
            2 * c * (xi - c) * w,
            w**4 + (xi - c) ** 2 * w**2 - F**2 / a**2,
        ]
    )
    r = np.sort(r[(np.abs(r.imag) <= 1e-9 * w) & (r.real > 0)].real)
    if r.size >= 2:
        return float(r[0]), float(r[-1])
    if r.size == 1:
        return float("nan"), float(r[0])
    return float("nan"), float("nan")


def _least_stiffness(w: np.ndarray, xi: np.ndarray, c: np.ndarray):
    """(W, h) with h the least over W of (w^2 - W^2)^2 + (xi w + c (W - w))^2 (Newton)."""
    W = w.copy()
    for _ in range(20):
        d1 = -4 * W * (w**2 - W**2) + 2 * c * (xi * w + c * (W - w))
        d2 = -4 * w**2 + 12 * W**2 + 2 * c**2
        W = W - d1 / np.where(np.abs(d2) > 0, d2, 1.0)
    return W, (w**2 - W**2) ** 2 + (xi * w + c * (W - w)) ** 2


def modal_force(nm: NlModeBranch, f1: object) -> np.ndarray:
    """``|psi_1^H f1|`` (N / sqrt(kg) per unit level) at every point of the backbone."""
    a = np.asarray(f1, dtype=complex).ravel()
    if a.shape != (nm.n,):
        raise InputError("f1", f"shape {a.shape}", f"{nm.n} complex amplitudes (N)")
    return np.abs(np.conj(nm.psi1()) @ a)


def synthesize(
    nm: NlModeBranch,
    f1: object,
    level: float,
    output: int = 0,
    band_hz: tuple[float, float] | None = None,
    mac_min: float = 0.9,
    separation: float = 0.05,
    higher_max: float = 0.2,
    damping_max: float = 0.15,
    others_max: float = 0.01,
) -> Synthesis:
    """The forced response at ``level`` (``f(t) = level Re(f1 exp(i W t))``) from the backbone.

    ``output``: which output of the backbone to report. ``band_hz`` clips
    the curve. The validity thresholds are described in the module
    docstring; a result outside them says why in ``reasons``.
    """
    level = check_range("level", level, 0.0, lo_open=True)
    if nm.n_points < 2:
        raise InputError("backbone", nm.n_points, "a backbone of at least two points")
    a = nm.amplitude
    w = TWO_PI * nm.freq_hz
    xi = nm.xi
    c = nm.xi_viscous
    F = modal_force(nm, f1) * level
    y = nm.out_amp[:, output]
    # the two sides of the resonance at every backbone amplitude: the real roots W > 0 of
    # W^4 + (c^2 - 2 w^2) W^2 + 2 c (xi - c) w W + w^4 + (xi - c)^2 w^2 - F^2 / a^2 = 0
    lo_f = np.full(a.size, np.nan)
    hi_f = np.full(a.size, np.nan)
    for i in range(a.size):
        lo_f[i], hi_f[i] = _sides(w[i], xi[i], c[i], F[i], a[i])
    # the peak: the first amplitude where the least of |modal dynamic stiffness| a over W
    # reaches the modal force
    W, h_min = _least_stiffness(w, xi, c)
    g = a * np.sqrt(h_min) - F
    reasons: list[str] = []
    hit = np.flatnonzero(g >= 0)
    linear_below = bool(nm.status.size == 0 or not np.any(nm.status[0]))
    if hit.size == 0:
        j, th = nm.n_points - 1, 1.0
        why = "" if nm.completed or not nm.message else f" (the backbone: {nm.message})"
        reasons.append(f"the peak lies beyond the largest amplitude of the backbone{why}")
    elif hit[0] == 0:
        # below the first point: linear if every contact sticks there (g and the outputs
        # are proportional to a), else out of reach
        j = 1
        th = float(-g[0] / (g[0] + F[0]) * a[0] / (a[1] - a[0])) if linear_below else 0.0
        if not linear_below:
            reasons.append("the peak lies below the smallest amplitude of the backbone")
    else:
        j = int(hit[0])
        th = float(-g[j - 1] / (g[j] - g[j - 1]))

    def at(v: np.ndarray) -> float:  # linear in the segment (j-1, j) of the backbone
        return float(v[j - 1] + th * (v[j] - v[j - 1]))

    # a segment where every contact sticks at both ends is linear: g and the outputs are
    # proportional to a; elsewhere they are interpolated in ln a (and ln y)
    stuck = nm.status.size == 0 or not (np.any(nm.status[j - 1]) or np.any(nm.status[j]))
    hy = nm.out_h1[:, output]
    scale = 1.0
    if th < 0:  # linear extrapolation below the first (stuck) point: shapes and rates fixed
        a_pk = float(a[0] + th * (a[1] - a[0]))
        scale = a_pk / a[0]

        def at(v: np.ndarray) -> float:  # noqa: F811
            return float(v[0])

        y_pk, h1_pk = y[0] * scale, hy[0] * scale
    elif stuck:
        a_pk = at(a)
        y_pk, h1_pk = at(y), at(hy)
    else:
        # within the segment: frequency, viscous rate and modal force linear in ln a, the
        # friction rate xi - c and the outputs per unit a log-linear (power laws, as for a
        # sliding contact); the root of g by bisection on that model
        s0, s1_ = np.log(a[j - 1]), np.log(a[j])

        def model(t: float):
            def lin(v):
                return v[j - 1] + t * (v[j] - v[j - 1])

            def loglin(v):  # linear where an end is (nearly) zero: the first slip
                if min(v[j - 1], v[j]) <= 1e-3 * max(v[j - 1], v[j], 1e-300):
                    return float(lin(v))
                l0, l1 = np.log(v[j - 1]), np.log(v[j])
                return float(np.exp(l0 + t * (l1 - l0)))

            cc = lin(c)
            return (lin(w), cc + loglin(xi - c), cc, lin(F), float(np.exp(s0 + t * (s1_ - s0))))

        def gt(t: float) -> float:
            ww, xx, cc, ff, aa = model(t)
            return float(
                aa * np.sqrt(_least_stiffness(np.array([ww]), np.array([xx]), np.array([cc]))[1][0])
                - ff
            )

        lo_t, hi_t = 0.0, 1.0
        if gt(lo_t) < 0 <= gt(hi_t):
            for _ in range(60):
                mid = 0.5 * (lo_t + hi_t)
                lo_t, hi_t = (mid, hi_t) if gt(mid) < 0 else (lo_t, mid)
            th = 0.5 * (lo_t + hi_t)
        a_pk = model(th)[4]

        def per_a(v):
            r = np.log(np.maximum(v, 1e-300) / a)
            return a_pk * float(np.exp(r[j - 1] + th * (r[j] - r[j - 1])))

        y_pk, h1_pk = per_a(y), per_a(hy)
    w_pk = at(w)
    xi_pk = at(xi)
    f_pk = at(W) / TWO_PI
    if hit.size and 0 <= th <= 1:  # a peak interpolated over a coarse segment
        a0, a1 = float(a[j - 1]), float(a[j])
        change = abs((y[j] / a1) / max(y[j - 1] / a0, 1e-300) - 1.0)
        on_point = min(abs(np.log(a_pk / a0)), abs(np.log(a_pk / a1))) < 1e-3
        if a1 > SEGMENT_MAX * a0 and change > SEGMENT_CHANGE and not on_point:
            reasons.append(
                f"the peak lies in a coarse segment of the backbone (modal amplitude "
                f"{a0:.4g} to {a1:.4g}) over which the output per modal amplitude changes "
                f"by {100 * change:.1f} %: not solved at the peak"
            )

    # the curve: both sides of the main branch (the backbone below the peak) and the peak
    # (between backbone points further apart than FLANK_RATIO in amplitude, e.g. across
    # the stuck range, which the continuation crosses in one step, the flanks are sampled
    # with w, xi, c and the modal force linear in ln a and the output per unit amplitude
    # log-linear: exact where the mode is linear, the backbone's own interpolation elsewhere)
    pts: list[tuple[float, float, float]] = []  # (left W, right W, output)

    def fill(i0: int, i1: int, a_end: float) -> None:
        if not a_end > FLANK_RATIO * a[i0] or not a[i1] > a[i0]:
            return
        n = int(np.ceil(np.log(a_end / a[i0]) / np.log(FLANK_RATIO)))
        r0, r1 = (np.log(max(y[i], 1e-300) / a[i]) for i in (i0, i1))
        for s_ in np.geomspace(a[i0], a_end, n + 1)[1:-1]:
            t = np.log(s_ / a[i0]) / np.log(a[i1] / a[i0])

            def lin(v: np.ndarray, t: float = t) -> float:
                return float(v[i0] + t * (v[i1] - v[i0]))

            lo, hi = _sides(lin(w), lin(xi), lin(c), lin(F), s_)
            pts.append((lo, hi, s_ * float(np.exp(r0 + t * (r1 - r0)))))

    idx = np.flatnonzero(np.arange(a.size) < j)
    for k, i in enumerate(idx):
        if k:
            fill(int(idx[k - 1]), int(i), a[i])
        pts.append((lo_f[i], hi_f[i], y[i]))
    if idx.size and th >= 0 and j < a.size:
        fill(j - 1, j, a_pk)
    P = np.array(pts, float).reshape(-1, 3)
    left, right = np.isfinite(P[:, 0]), np.isfinite(P[:, 1])
    curve_f = np.concatenate([P[left, 0] / TWO_PI, [f_pk], P[right, 1][::-1] / TWO_PI])
    curve_y = np.concatenate([P[left, 2], [y_pk], P[right, 2][::-1]])
    if band_hz is not None:
        keep = (curve_f >= band_hz[0]) & (curve_f <= band_hz[1])
        curve_f, curve_y = curve_f[keep], curve_y[keep]
    if np.any(np.diff(a[: j + 1]) < -1e-9 * a[:j].max(initial=0.0)):
        reasons.append(
            "the backbone folds back in amplitude below the peak (the mode "
            "changes character: modal interaction)"
        )
    # validity at the peak
    mac = at(nm.mac)
    hh = float(np.max(nm.higher_harmonics[: j + 1]))
    d_pk = xi_pk / (2 * w_pk)
    others = np.delete(nm.linear_hz, nm.mode)
    gap = float(np.min(np.abs(others - f_pk)) / f_pk) if others.size else np.inf
    if mac < mac_min:
        reasons.append(
            f"the mode shape changes with amplitude (MAC {mac:.3f} < {mac_min:g} "
            "against the low-amplitude shape)"
        )
    if gap < separation:
        reasons.append(
            f"another linear mode lies within {100 * gap:.1f} % of the peak "
            "frequency (modal interaction)"
        )
    if hh > higher_max:
        reasons.append(
            f"higher harmonics carry {100 * hh:.0f} % of the motion (internal resonance?)"
        )
    others = nm.other_modes_response(np.asarray(f1, complex), f_pk)
    share = float(np.abs(others[output]) * level / y_pk) if y_pk > 0 and others.size else 0.0
    if share > others_max:
        reasons.append(
            f"the other modes add {100 * share:.1f} % of the peak amplitude (their "
            "stuck linear response there): the forced motion is not the mode alone"
        )
    if d_pk > damping_max:
        reasons.append(f"damping ratio {d_pk:.3f} > {damping_max:g} at the peak")
    # a second crossing further up: the full curve may have an isola or a jump there
    if hit.size and np.any(g[hit[0] :] < 0):
        reasons.append(
            "the modal force meets the dissipation again at a larger amplitude "
            "(isolated branch possible)"
        )
    blocking = [r for r in reasons if not r.startswith("the modal force meets")]
    return Synthesis(
        level=float(level),
        freq_hz=curve_f,
        out_amp=curve_y,
        peak_freq_hz=f_pk,
        peak_amplitude=y_pk,
        peak_modal_amplitude=a_pk,
        valid=not blocking,
        reasons=reasons,
        peak_h1=h1_pk,
        checks=dict(
            mac=mac, separation=gap, higher_harmonics=hh, damping_ratio=d_pk, other_modes=share
        ),
    )
