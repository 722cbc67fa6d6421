"""The harmonic balance's periodic state against a run-up from rest, on small models.

A stuck friction element's locked-in force is not fixed by the periodic
equations; the contact march picks it by a history rule
(:mod:`workbench.contact.march`). This module checks that rule against the
history a real vibration has: a run-up from the preload state
(:func:`.runup.runup`), the excitation switched on or ramped in,
integrated until its periods repeat. It compares, at one frequency,

* the output's harmonic-0 (mean) and harmonic-1 amplitude;
* each element's mean tangential force and locked-in force
  ``T - kt u`` (constant over the period while it sticks);
* the harmonic balance residual of the run-up's own last period, under a
  given march rule (``growth``): how far the run-up's periodic state is
  from a solution of the harmonic balance equations.

Used by ``benchmarks/runup_mean_position.py`` and
``tests/test_runup_mean_position.py``; see docs/notes/mean_position.md.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...contact import get_law
from ...contact.march import march
from ...errors import SolveError
from ..core.balance import HarmonicBalance
from ..core.ports import observation
from .runup import runup


@dataclass
class PeriodicState:
    """One periodic state at one frequency: from the harmonic balance or a run-up."""

    mean: np.ndarray  # (n_out,) harmonic-0 of each output, m
    h1: np.ndarray  # (n_out,) harmonic-1 amplitude of each output, m
    t_mean: np.ndarray  # (n_el, 2) mean tangential force, N
    locked: np.ndarray  # (n_el, 2) T - kt u averaged over the period, N
    locked_spread: np.ndarray  # (n_el, 2) max - min of T - kt u over the period, N
    n_slip: np.ndarray  # (n_el,) slipping samples in the period
    u: np.ndarray  # (n_el, nt, 3) contact displacement samples, m
    f: np.ndarray  # (n_el, nt, 3) contact force samples, N
    periods: int = 0  # run-up: periods integrated (ramp included)
    settled: int = -1  # run-up: first period from which every period repeats to tol


def _forces(el, u: np.ndarray, f: np.ndarray, n_slip) -> dict:
    c = f[:, :, :2] - np.stack([el.kt1, el.kt2], axis=1)[:, None, :] * u[:, :, :2]
    return dict(
        t_mean=f[:, :, :2].mean(axis=1),
        locked=c.mean(axis=1),
        locked_spread=c.max(axis=1) - c.min(axis=1),
        n_slip=np.asarray(n_slip),
        u=u,
        f=f,
    )


def solve_hbm(
    hb: HarmonicBalance, freq_hz: float, x0: np.ndarray, tol: float = 1e-10, max_it: int = 60
) -> np.ndarray:
    """Newton's method on the harmonic balance at one frequency from ``x0``; the unknowns."""
    w = 2.0 * np.pi * freq_hz
    x = np.array(x0, dtype=float)
    for _ in range(max_it):
        ev = hb.evaluate(x, w)
        dx = np.linalg.solve(hb.dense_jacobian(ev), -ev.r)
        x = x + dx
        if np.abs(dx).max() <= tol * max(np.abs(x).max(), 1e-300):
            return x
    raise SolveError(f"harmonic balance at {freq_hz:.6g} Hz: Newton did not converge")


def hbm_state(hb: HarmonicBalance, x: np.ndarray, freq_hz: float) -> PeriodicState:
    """The periodic state of the harmonic balance at unknowns ``x``."""
    ev = hb.evaluate(x, 2.0 * np.pi * freq_hz)
    Y = hb._rmul(ev.Yz, hb.Oz.T)
    return PeriodicState(
        mean=Y[0].copy() if hb.fourier.has_dc else np.zeros(Y.shape[1]),
        h1=hb.fourier.h1_amplitude(Y),
        **_forces(hb.el, ev.aft.u, ev.aft.f, ev.aft.n_slip),
    )


def runup_state(
    system,
    f1: np.ndarray,
    level: float,
    freq_hz: float,
    outputs: np.ndarray,
    ramp_periods: float,
    max_periods: int = 4000,
    tol: float = 1e-7,
    steps_per_period: int = 128,
    chunk: int = 20,
) -> PeriodicState:
    """Integrate from rest until the periods repeat; the state of one more period.

    The periods repeat when the output's harmonic-1 amplitude and mean
    change by less than ``tol`` times the amplitude from one period to the
    next over a whole ``chunk`` after the ramp; ``settled`` is the first
    period from which that holds. Then one more period is integrated and
    its contact forces replayed from the law's state before it.
    """
    el = system.contacts
    outputs = observation(system, outputs)
    n_out = outputs.shape[0]
    O = np.vstack([outputs, el.W.toarray()])
    law = get_law(el.law)
    start, done, settled = None, 0, -1
    h1s, means = [], []
    while True:
        ru = runup(
            system, f1, level, freq_hz, O, periods=chunk, steps_per_period=steps_per_period,
            ramp_periods=ramp_periods, start=start, chunk=chunk,
        )  # fmt: skip
        start, done = ru.state, done + chunk
        h1s.append(ru.h1[:, :n_out])
        means.append(ru.mean[:, :n_out])
        h1, mean = np.concatenate(h1s), np.concatenate(means)
        scale = h1[-1].max()
        chg = np.maximum(np.abs(np.diff(h1, axis=0)), np.abs(np.diff(mean, axis=0))).max(axis=1)
        big = np.flatnonzero(chg > tol * scale)
        settled = int(big[-1]) + 2 if big.size else 1  # 1-based period after the last change
        if done > ramp_periods and done - settled >= chunk:
            break
        if done >= max_periods:
            raise SolveError(
                f"run-up at {freq_hz:.6g} Hz: periods still change by "
                f"{chg[-1] / scale:.2g} of the amplitude after {done} periods"
            )
    s0 = np.array(start["s"])
    ru = runup(system, f1, level, freq_hz, O, periods=1, steps_per_period=steps_per_period,
               ramp_periods=ramp_periods, start=start)  # fmt: skip
    y = ru.last
    u = np.ascontiguousarray(y[:, n_out:].reshape(-1, el.n_el, 3).transpose(1, 0, 2))
    f, n_slip = replay(law, el, u, s0)
    # the run-up's sample j is at time (j + 1) dt, the harmonic balance's sample k at k dt
    u, f = np.roll(u, 1, axis=1), np.roll(f, 1, axis=1)
    t = 2 * np.pi * np.arange(1, y.shape[0] + 1) / y.shape[0]
    return PeriodicState(
        mean=y[:, :n_out].mean(axis=0),
        h1=np.abs(np.exp(-1j * t) @ y[:, :n_out]) * 2 / y.shape[0],
        periods=done + 1,
        settled=settled,
        **_forces(el, u, f, n_slip),
    )


def replay(law, el, u: np.ndarray, s0: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The law's forces (n_el, nt, 3) and slipping samples over samples ``u`` from state ``s0``."""
    n_el, nt, _ = u.shape
    ns = law.n_state
    f = np.zeros((n_el, nt, 3))
    n_slip = np.zeros(n_el, dtype=int)
    Fu, Fs, Su, Ss = np.zeros((3, 3)), np.zeros((3, ns)), np.zeros((ns, 3)), np.zeros((ns, ns))
    for e in range(n_el):
        s = np.array(s0[e], dtype=float)
        for j in range(nt):
            s_new = np.zeros(ns)
            fj = np.zeros(3)
            flag = law.step(
                np.ascontiguousarray(u[e, j]), s, el.mu[e], el.kt1[e], el.kt2[e], el.kn[e],
                el.n0[e], el.lp[e], False, fj, s_new, Fu, Fs, Su, Ss,
            )  # fmt: skip
            f[e, j] = fj
            n_slip[e] += flag == 1
            s = s_new
    return f, n_slip


def residual_of(hb: HarmonicBalance, u: np.ndarray, freq_hz: float, growth: int = 0):
    """The harmonic balance residual at the harmonics of contact samples ``u`` (n_el, nt, 3).

    ``u`` in the harmonic balance's sample order (sample ``k`` at ``k T / nt``;
    a multiple of ``nt`` samples is thinned to ``nt``).
    ``growth``: the march's growth periods (default 0, the harmonic
    balance's own contact march: from rest). Returns
    ``(|r| / |x|, x)`` with ``x`` the unknowns (condensed space: the active
    contact DOFs' harmonics).
    """
    if hb.space != "condensed":
        raise SolveError("residual_of needs the condensed space (contact DOFs as unknowns)")
    f = hb.fourier
    if u.shape[1] != f.nt:
        if u.shape[1] % f.nt:
            raise SolveError(f"{u.shape[1]} samples per period: not a multiple of nt = {f.nt}")
        u = u[:, :: u.shape[1] // f.nt]
    U = (f.P @ u.transpose(1, 0, 2).reshape(u.shape[1], -1)).reshape(f.nh, -1)
    x = U[:, hb.act].ravel()
    w = 2.0 * np.pi * freq_hz
    X = x.reshape(f.nh, hb.n_s)
    Uall = hb.to_u(X).reshape(f.nh, hb.n_el, 3)
    el = hb.el
    ut = np.ascontiguousarray(
        (f.E @ Uall.reshape(f.nh, -1)).reshape(f.nt, hb.n_el, 3).transpose(1, 0, 2)
    )
    out = march(
        ut, f.E, f.P, el.mu, el.kt1, el.kt2, el.kn, el.n0, el.law, False,
        active=el.active, lp=el.lp, growth=growth,
    )  # fmt: skip
    Floc = np.ascontiguousarray(out["F"].transpose(2, 0, 1))
    G = (Floc - hb.kc[None] * Uall).reshape(f.nh, hb.n3)
    Yz = hb.lin.solve(w, hb.Pz - hb._rmul(G, hb.Bz))
    r = (X - hb._left(Yz)).ravel()
    return float(np.linalg.norm(r) / np.linalg.norm(x)), x
