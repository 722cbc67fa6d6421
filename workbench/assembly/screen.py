"""The coupling screen: will a damper level a family's peak off? (linear, seconds)

A friction damper can only limit a resonance as far as it stiffens the mode
when it sticks. For one excitation pattern (an inter-blade phase angle) and
one assembled rig + damper, the linear limits bracket the nonlinear answer:

* ``f_stuck``: every contact pair stuck and closed (springs ``kt, kt, kn``);
* ``f_slide``: tangential springs removed, normal springs kept (a damper
  that slips freely);
* ``k2/k = 1 - (f_slide / f_stuck)^2``: the share of the stuck mode's
  modal stiffness that the sticking damper adds;
* the *rig bound* on ``k2/k``: the same with a rigid damper and contact
  springs ``stiff_factor`` (1000) times stiffer, the most coupling the
  rig's own kinematics allows, whatever the damper and its contact;
* ``F_slip``: the excitation (N per blade) at which the first pair reaches
  its slip limit ``mu N(t)`` in the stuck linear response (the normal load
  varies with the response); ``F_sep``: the excitation at which the first
  pair's normal load reaches zero;
* ``F_cap``: the single-mode Jenkins estimate of the force up to which the
  peak stays level, ``F_cap / F_slip = (4 / pi) Q k2/k`` with ``Q = 1 /
  (2 zeta)``. It follows from a modal oscillator of stiffness ``k - k2`` with
  a friction element (stiffness ``k2``, slip force ``S``) in parallel: stuck,
  the resonant amplitude is ``X = Q F / k``, so slip starts at ``F_slip = S k
  / (Q k2)``; sliding, friction absorbs the whole input at resonance while
  ``F < 4 S / pi``.

The same single-mode model gives the peak at any force: linear
``A = r F`` up to ``F_slip`` (``r`` the stuck peak receptance), then, from
the energy balance at resonance (input = friction + viscous dissipation),

    A(F) = (r / 2) [F - F_cap + sqrt((F_cap - F)^2 + 4 F_cap F_slip)]

which stays near ``r F_slip F_cap / (F_cap - F)`` well below ``F_cap``. On a
single-DOF Jenkins oscillator it is within 0.4 % of the harmonic balance up
to 0.3 ``F_cap`` and within 1.1 % at 0.6 ``F_cap`` (tests/test_screen.py).
Beyond ``F_cap`` the response moves to the sliding resonance and the
estimate is a lower bound (26 % low at 1.26 ``F_cap``). :meth:`ScreenResult.peak_m`
evaluates it; ``growth`` is the predicted ``A(F_max) / A(0.32 F_max)`` (the
paper's 30 N over 9.6 N). Verdict for the largest force of interest
``F_max``: ``"stuck"`` when ``F_slip > F_max`` (the damper never slips),
``"levels off"`` when the predicted growth is at most 1.3, ``"damps"``
otherwise (the peak keeps rising with the force, more slowly than a
linear response). A ``k2/k`` of a few per cent cannot level a peak off,
whatever ``mu`` and the centrifugal load: ``F_cap`` is then within a few
``F_slip``.

Everything here is dense linear algebra on the reduced model (a few hundred
DOFs): milliseconds. The cost of a screen is that of the FE reduction that
feeds it (cached between runs).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np
import scipy.sparse as sp

from ..errors import InputError, check_range
from .linear import family_frequency, modes

STIFF_FACTOR = 1000.0  # contact stiffening of the rig bound
N_TIME = 64  # samples per period of the slip/separation onset search
N_FREQ = 161  # frequencies of the onset search, over +-4 half-power bandwidths
REF_RATIO = 0.32  # growth is measured from 0.32 F_max to F_max (9.6 N to 30 N in the paper)
LEVEL_GROWTH = 1.3  # a predicted growth up to this is "levels off"


def predicted_peak(r: float, f_slip: float, f_cap: float, force: float) -> float:
    """Peak response (m) of the single-mode friction model at ``force`` (N).

    ``r``: stuck peak receptance (m/N); ``f_slip``, ``f_cap`` (N) as in the
    module docstring. Linear below slip onset; energy balance above it.
    """
    if not force > f_slip:
        return r * force
    d = f_cap - force
    return 0.5 * r * (-d + math.sqrt(d * d + 4.0 * f_cap * f_slip))


@dataclass(frozen=True)
class LinearPair:
    """A linear system with friction contact pairs, as plain arrays (SI units).

    ``W`` (3 n_pairs x n) maps coordinates to each pair's ``[t1, t2, n]``
    relative displacement; ``kt``, ``kn`` (N/m), ``mu`` (-), ``n0`` (N,
    compressive positive) per pair; ``f1`` (n, complex) the harmonic force
    pattern per newton; ``r`` (n) the response row.
    """

    M: np.ndarray
    K: np.ndarray
    W: sp.csr_matrix
    kt: np.ndarray
    kn: np.ndarray
    mu: np.ndarray
    n0: np.ndarray
    f1: np.ndarray
    r: np.ndarray

    def stiffness(self, limit: str, factor: float = 1.0) -> np.ndarray:
        """``K + W^T diag(kt, kt, kn) W`` (stuck) or with ``kt = 0`` (sliding), N/m."""
        kt = self.kt * factor if limit == "stuck" else 0.0 * self.kt
        kc = np.stack([kt, kt, self.kn * factor], axis=1).ravel()
        W = self.W
        return self.K + (W.T @ W.multiply(kc.reshape(-1, 1))).toarray()


@dataclass(frozen=True)
class ScreenResult:
    """One damper, one excitation pattern: the linear coupling screen (module docstring)."""

    phase_deg: float
    f_stuck_hz: float
    f_slide_hz: float
    k2_over_k: float
    bound_f_stuck_hz: float | None  # rigid damper, contact x STIFF_FACTOR
    bound_f_slide_hz: float | None
    bound_k2_over_k: float | None
    zeta: float
    q_factor: float
    stuck_peak_m_per_n: float  # |response| per newton at the stuck resonance
    slide_peak_m_per_n: float  # the same for the sliding limit (viscous damping only)
    f_slip_n: float  # inf when no pair ever slips
    f_sep_n: float  # inf when no pair ever separates
    f_cap_n: float
    slip_pair: int  # the pair that slips first (-1: none)
    sep_pair: int
    f_max_n: float | None = None
    growth: float | None = None  # predicted A(F_max) / A(REF_RATIO F_max)
    verdict: str = ""

    def peak_m(self, force_n: float) -> float:
        """Single-mode estimate of the peak response (m) at ``force_n`` (module docstring)."""
        return predicted_peak(self.stuck_peak_m_per_n, self.f_slip_n, self.f_cap_n, force_n)

    @property
    def family(self) -> str:
        ph = self.phase_deg % 360.0
        if abs(ph) < 1e-9 or abs(ph - 360.0) < 1e-9:
            return "in-phase"
        if abs(ph - 180.0) < 1e-9:
            return "out-of-phase"
        return f"{self.phase_deg:g} deg"

    def as_dict(self) -> dict:
        d = asdict(self)
        d["family"] = self.family
        d["cap_over_slip"] = (
            self.f_cap_n / self.f_slip_n
            if math.isfinite(self.f_slip_n) and self.f_slip_n > 0
            else None
        )
        for k, v in list(d.items()):
            if isinstance(v, float) and not math.isfinite(v):
                d[k] = None  # JSON has no inf: None reads "never" (see *_pair = -1)
        return d


def _modal_response(
    lam: np.ndarray,
    phi: np.ndarray,
    vecs: np.ndarray,
    f1: np.ndarray,
    omegas: np.ndarray,
    zeta: float,
) -> np.ndarray:
    """``vecs @ X(omega)`` for every omega, by modal superposition with ratio ``zeta``.

    ``phi`` mass-normalised; rigid modes (lam ~ 0) carry no static force and
    are dropped. Returns (n_omega, n_vecs) complex.
    """
    wn = np.sqrt(np.maximum(lam, 0.0))
    keep = wn > 1e-6 * wn.max()
    wn, phi = wn[keep], phi[:, keep]
    modal_f = phi.T @ f1  # (m,)
    proj = vecs @ phi  # (n_vecs, m)
    den = wn[None, :] ** 2 - omegas[:, None] ** 2 + 2j * zeta * wn[None, :] * omegas[:, None]
    return (modal_f[None, :] / den) @ proj.T


def onset_forces(
    sys_: LinearPair, zeta: float, f_center_hz: float, law: str = "decoupled"
) -> tuple[float, int, float, int, float]:
    """Slip and separation onset forces of the stuck linear response near ``f_center_hz``.

    The stuck response per newton gives, per pair, the tangential force
    ``T(t) = F tau(t)`` and the normal load ``N(t) = N0 + F nu(t)``. A pair
    slips at the smallest ``F`` where ``|T| = mu N`` at some instant:
    ``F = mu N0 / (|tau| - mu nu)`` (``|tau|`` the largest component for the
    decoupled law, the vector norm for the circular law); it separates at
    ``F = N0 / max(-nu)``. The minimum is taken over the pairs, ``N_TIME``
    instants per period and ``N_FREQ`` frequencies spanning +-4 half-power
    bandwidths around the stuck resonance.

    Returns (F_slip, pair, F_sep, pair, stuck peak |response| per newton).
    """
    Ks = sys_.stiffness("stuck")
    lam, phi = modes(Ks, sys_.M)
    w0 = 2 * np.pi * f_center_hz
    omegas = w0 * (1 + 4 * max(zeta, 1e-4) * np.linspace(-1, 1, N_FREQ))
    n_p = sys_.kt.size
    Wd = sys_.W.toarray()
    out = _modal_response(lam, phi, np.vstack([Wd, sys_.r[None, :]]), sys_.f1, omegas, zeta)
    resp = np.abs(out[:, -1]).max()
    u = out[:, :-1].reshape(omegas.size, n_p, 3)  # complex amplitude per newton
    th = np.linspace(0, 2 * np.pi, N_TIME, endpoint=False)
    ph = np.exp(1j * th)  # (nt,)
    ut = np.real(u[:, :, None, :] * ph[None, None, :, None])  # (nw, np, nt, 3)
    t1 = sys_.kt[None, :, None] * ut[..., 0]
    t2 = sys_.kt[None, :, None] * ut[..., 1]
    nu = -sys_.kn[None, :, None] * ut[..., 2]  # n > 0 opens: the load falls
    tau = np.maximum(np.abs(t1), np.abs(t2)) if law == "decoupled" else np.hypot(t1, t2)
    mu = sys_.mu[None, :, None]
    n0 = sys_.n0[None, :, None]
    den = tau - mu * nu
    with np.errstate(divide="ignore", invalid="ignore"):
        f_slip = np.where(den > 1e-300, mu * n0 / den, np.inf)
        f_sep = np.where(-nu > 1e-300, n0 / (-nu), np.inf)
    per_pair_slip = f_slip.min(axis=(0, 2))
    per_pair_sep = f_sep.min(axis=(0, 2))
    i_slip = int(np.argmin(per_pair_slip))
    i_sep = int(np.argmin(per_pair_sep))
    fs, fp = float(per_pair_slip[i_slip]), float(per_pair_sep[i_sep])
    return (
        fs,
        i_slip if math.isfinite(fs) else -1,
        fp,
        i_sep if math.isfinite(fp) else -1,
        float(resp),
    )


def screen(
    sys_: LinearPair,
    zeta: float,
    *,
    phase_deg: float = 0.0,
    bound: LinearPair | None = None,
    law: str = "decoupled",
    f_max_n: float | None = None,
) -> ScreenResult:
    """The coupling screen of one system and excitation pattern (module docstring).

    ``zeta``: modal damping ratio of the stuck modes (> 0). ``bound``: the
    same rig with a rigid damper (its contact springs are multiplied by
    ``STIFF_FACTOR`` here), or None to skip the rig bound. ``f_max_n``: the
    largest excitation of interest, for the verdict.
    """
    zeta = check_range("zeta", zeta, 0.0, 0.5, lo_open=True)
    if law not in ("decoupled", "circular"):
        raise InputError("law", law, "decoupled or circular")
    fam_st = family_frequency(sys_.M, sys_.stiffness("stuck"), sys_.f1, sys_.r)
    fam_sl = family_frequency(sys_.M, sys_.stiffness("sliding"), sys_.f1, sys_.r)
    k2k = 1.0 - (fam_sl.freq_hz / fam_st.freq_hz) ** 2
    b_st = b_sl = b_k = None
    if bound is not None:
        b_st = family_frequency(
            bound.M, bound.stiffness("stuck", STIFF_FACTOR), bound.f1, bound.r
        ).freq_hz
        b_sl = family_frequency(
            bound.M, bound.stiffness("sliding", STIFF_FACTOR), bound.f1, bound.r
        ).freq_hz
        b_k = 1.0 - (b_sl / b_st) ** 2
    fs, i_s, fp, i_p, resp = onset_forces(sys_, zeta, fam_st.freq_hz, law)
    # the sliding limit's peak (viscous damping only): where the response goes once the
    # damper slides through
    lam, phi = modes(sys_.stiffness("sliding"), sys_.M)
    w_sl = 2 * np.pi * fam_sl.freq_hz
    om = w_sl * (1 + 4 * max(zeta, 1e-4) * np.linspace(-1, 1, N_FREQ))
    slide_peak = float(np.abs(_modal_response(lam, phi, sys_.r[None, :], sys_.f1, om, zeta)).max())
    q = 1.0 / (2.0 * zeta)
    f_cap = (4.0 / math.pi) * q * max(k2k, 0.0) * fs
    growth = None
    verdict = ""
    if f_max_n is not None:
        growth = predicted_peak(resp, fs, f_cap, f_max_n) / predicted_peak(
            resp, fs, f_cap, REF_RATIO * f_max_n
        )
        if not fs <= f_max_n:
            verdict = "stuck"
        elif growth <= LEVEL_GROWTH:
            verdict = "levels off"
        else:
            verdict = "damps"
        if fp <= f_max_n:
            verdict += ", separates"  # the single-mode estimate ignores lift-off
    return ScreenResult(
        phase_deg=float(phase_deg),
        f_stuck_hz=fam_st.freq_hz,
        f_slide_hz=fam_sl.freq_hz,
        k2_over_k=float(k2k),
        bound_f_stuck_hz=b_st,
        bound_f_slide_hz=b_sl,
        bound_k2_over_k=b_k,
        zeta=float(zeta),
        q_factor=q,
        stuck_peak_m_per_n=resp,
        slide_peak_m_per_n=slide_peak,
        f_slip_n=fs,
        f_sep_n=fp,
        f_cap_n=float(f_cap),
        slip_pair=i_s,
        sep_pair=i_p,
        f_max_n=f_max_n,
        growth=growth,
        verdict=verdict,
    )


def linear_pair(model, phase_deg: float, response_blade: int = 1) -> LinearPair:
    """A :class:`LinearPair` from an :class:`~workbench.assembly.model.AssembledModel`."""
    return LinearPair(
        M=model.M,
        K=model.K,
        W=model.W,
        kt=model.kt,
        kn=model.kn,
        mu=model.mu,
        n0=model.n0,
        f1=model.excitation(phase_deg),
        r=model.response_dofs[response_blade - 1],
    )
