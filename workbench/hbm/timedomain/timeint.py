"""Time-integration reference: the same model and contact law, marched to steady state.

Newmark's average-acceleration rule (``beta = 1/4``, ``gamma = 1/2``,
unconditionally stable, no numerical damping) with a fixed step of
``T / steps_per_period``; at each step the contact law of
the law's own ``step`` (:mod:`workbench.contact.laws`, the same function
the harmonic balance marches) is solved with Newton's method and its
consistent tangent ``df/du``; a step whose Newton does not converge (60
iterations, correction below 1e-12 of the displacement) is rejected: the
integration stops with a :class:`SolveError` naming the time. Periods are
run until the state at the end of a period repeats the previous one within
``tol`` (relative) twice in a row; the last period is the steady periodic
response.

Compiled with numba (one kernel per law) for dense matrices: meant for the small models used to
check the harmonic balance (a few dozen DOFs), at chosen frequencies.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...contact import get_law
from ...contact.march import specialise
from ...errors import InputError, SolveError, check_int, check_range
from ..core.fourier import Fourier
from ..core.ports import excitation_vector, observation
from ..core.system import System


@dataclass
class TimeResponse:
    """Steady periodic response from time integration at one frequency."""

    freq_hz: float
    t: np.ndarray  # (spp,) s, one period (t = 0 excluded, t = T included)
    y: np.ndarray  # (spp, n_out) outputs over the last period (model length unit)
    amplitude: np.ndarray  # (n_out,) max |y| over the period
    harmonics: np.ndarray  # (nh, n_out) Fourier coefficients of y on the requested list
    h1_amplitude: np.ndarray  # (n_out,)
    status: np.ndarray  # (n_el,) 0 stuck, 1 stick-slip, 2 partial, 3 full separation
    friction_energy: np.ndarray  # (n_el,) J per cycle (trapezoid on the loop)
    periods: int
    converged: bool
    q_end: np.ndarray  # (n,) state at the end, to restart from
    v_end: np.ndarray


step = None  # the law's step: bound per law by contact.march.specialise


def _newmark_py(
    ns,
    M,
    C,
    K,
    Wd,
    mu,
    kt1,
    kt2,
    kn,
    n0,
    lp,
    fs,
    fc,
    fsn,
    omega,
    spp,
    max_periods,
    tol,
    q0,
    v0,
    qbuf,
    slip_cnt,
    sep_cnt,
    efric,
):
    n_el = Wd.shape[0] // 3
    n = M.shape[0]
    T = 2.0 * np.pi / omega
    dt = T / spp
    beta, gamma = 0.25, 0.5
    Khat = K + (gamma / (beta * dt)) * C + (1.0 / (beta * dt * dt)) * M
    q = q0.copy()
    v = v0.copy()
    state = np.zeros((n_el, ns))
    s_new = np.zeros((n_el, ns))
    f = np.zeros((n_el, 3))
    Kt = np.zeros((n_el, 3, 3))
    Fs = np.zeros((3, ns))
    Su = np.zeros((ns, 3))
    Ss = np.zeros((ns, ns))
    flags = np.zeros(n_el, dtype=np.int64)
    u = (Wd @ q).reshape(n_el, 3)
    for e in range(n_el):
        step(u[e], state[e], mu[e], kt1[e], kt2[e], kn[e], n0[e], lp[e], False,
             f[e], s_new[e], Kt[e], Fs, Su, Ss)  # fmt: skip
    state[:, :] = s_new
    fcont = Wd.T @ f.ravel()
    a = np.linalg.solve(M, fs + fc - C @ v - K @ q - fcont)
    q_prev_end = q.copy()
    v_prev_end = v.copy()
    n_ok = 0
    t = 0.0
    for p in range(max_periods):
        for e in range(n_el):
            slip_cnt[e] = 0
            sep_cnt[e] = 0
            efric[e] = 0.0
        qmax = 1e-300
        vmax = 1e-300
        for j in range(spp):
            t = (p * spp + j + 1) * dt
            load = fs + fc * np.cos(omega * t) + fsn * np.sin(omega * t)
            rhs = (
                load
                + M @ (q / (beta * dt * dt) + v / (beta * dt) + (0.5 / beta - 1.0) * a)
                + C
                @ (
                    (gamma / (beta * dt)) * q
                    + (gamma / beta - 1.0) * v
                    + dt * (0.5 * gamma / beta - 1.0) * a
                )
            )
            qn = q + dt * v + 0.5 * dt * dt * a
            u_old = (Wd @ q).reshape(n_el, 3)
            f_old = f.copy()
            converged = n == 0
            for _ in range(60):
                u = (Wd @ qn).reshape(n_el, 3)
                for e in range(n_el):
                    flags[e] = step(u[e], state[e], mu[e], kt1[e], kt2[e], kn[e], n0[e],
                                    lp[e], True, f[e], s_new[e], Kt[e], Fs, Su, Ss)  # fmt: skip
                r = Khat @ qn + Wd.T @ f.ravel() - rhs
                Jt = Khat.copy()
                Kb = np.zeros((3 * n_el, 3 * n_el))
                for e in range(n_el):
                    for aa in range(3):
                        for bb in range(3):
                            Kb[3 * e + aa, 3 * e + bb] = Kt[e, aa, bb]
                Jt += Wd.T @ Kb @ Wd
                dq = np.linalg.solve(Jt, -r)
                qn = qn + dq
                if np.abs(dq).max() <= 1e-12 * (np.abs(qn).max() + 1e-300):
                    converged = True
                    break
            if not converged:
                return p, False, q, v, t
            u = (Wd @ qn).reshape(n_el, 3)
            for e in range(n_el):
                flags[e] = step(u[e], state[e], mu[e], kt1[e], kt2[e], kn[e], n0[e], lp[e],
                                False, f[e], s_new[e], Kt[e], Fs, Su, Ss)  # fmt: skip
            an = (qn - q) / (beta * dt * dt) - v / (beta * dt) - (0.5 / beta - 1.0) * a
            vn = v + dt * ((1.0 - gamma) * a + gamma * an)
            for e in range(n_el):
                efric[e] += 0.5 * (
                    (f[e, 0] + f_old[e, 0]) * (u[e, 0] - u_old[e, 0])
                    + (f[e, 1] + f_old[e, 1]) * (u[e, 1] - u_old[e, 1])
                )
                if flags[e] == 1:
                    slip_cnt[e] += 1
                elif flags[e] == 2:
                    sep_cnt[e] += 1
            state[:, :] = s_new
            q, v, a = qn, vn, an
            qbuf[j] = q
            qmax = max(qmax, np.abs(q).max())
            vmax = max(vmax, np.abs(v).max())
        err = max(np.abs(q - q_prev_end).max() / qmax, np.abs(v - v_prev_end).max() / vmax)
        q_prev_end = q.copy()
        v_prev_end = v.copy()
        if err <= tol:
            n_ok += 1
            if n_ok >= 2:
                return p + 1, True, q, v, -1.0
        else:
            n_ok = 0
    return max_periods, False, q, v, -1.0


def time_response(
    system: System,
    f1: np.ndarray,
    level: float,
    freq_hz: float,
    outputs: object = None,
    harmonics: tuple[int, ...] = (0, 1, 2, 3, 4, 5, 6, 7),
    steps_per_period: int = 1024,
    max_periods: int = 5000,
    tol: float = 1e-9,
    q0: np.ndarray | None = None,
    v0: np.ndarray | None = None,
) -> TimeResponse:
    """Steady response to ``level * Re(f1 exp(i w t))`` at ``freq_hz`` by time integration.

    ``outputs`` as for :func:`workbench.hbm.frequency_response`. ``q0``,
    ``v0``: initial state (default rest at the static equilibrium ``u = 0``);
    starting near the expected orbit saves periods. Raises
    :class:`SolveError` (with the last period as ``partial``) if the
    response does not repeat within ``tol`` after ``max_periods``.
    """
    freq = check_range("freq_hz", freq_hz, 0.0, lo_open=True, unit="Hz")
    spp = check_int("steps_per_period", steps_per_period, 16)
    max_periods = check_int("max_periods", max_periods, 1)
    level = check_range("level", level, 0.0)
    n = system.n
    if n > 200:
        raise InputError("system.n", n, "at most 200 DOFs for the dense time-integration reference")
    F = level * excitation_vector(system, f1)
    O = observation(system, outputs)
    C = system.damping_matrix()
    el = system.contacts
    if el is None:
        Wd = np.zeros((0, n))
        arrs = [np.zeros(0)] * 5 + [np.zeros((0, 0))]
        law = get_law("decoupled")
    else:
        Wd = el.W.toarray()
        arrs = [el.mu, el.kt1, el.kt2, el.kn, el.n0, el.lp]
        law = get_law(el.law)
    n_el = Wd.shape[0] // 3
    qb = np.zeros((spp, n))
    slip = np.zeros(n_el, dtype=np.int64)
    sep = np.zeros(n_el, dtype=np.int64)
    ef = np.zeros(n_el)
    q0 = np.zeros(n) if q0 is None else np.asarray(q0, dtype=float).copy()
    v0 = np.zeros(n) if v0 is None else np.asarray(v0, dtype=float).copy()
    periods, ok, qe, ve, t_bad = specialise(_newmark_py, law, "_newmark")(
        law.n_state,
        system.M,
        C,
        system.K,
        Wd,
        *arrs,
        system.total_static_force(),
        F.real.copy(),
        -F.imag.copy(),
        2 * np.pi * freq,
        spp,
        max_periods,
        float(tol),
        q0,
        v0,
        qb,
        slip,
        sep,
        ef,
    )
    T = 1.0 / freq
    t = T * np.arange(1, spp + 1) / spp
    y = qb @ O.T
    four = Fourier(tuple(harmonics), spp)
    # samples at t_j = (j+1) T/spp: rotate so that index 0 is t = 0 (= t = T)
    X = four.P @ np.roll(y, 1, axis=0)
    from ...contact import classify

    res = TimeResponse(
        freq_hz=freq,
        t=t,
        y=y,
        amplitude=np.abs(y).max(axis=0),
        harmonics=X,
        h1_amplitude=four.h1_amplitude(X),
        status=classify(slip, sep, spp),
        friction_energy=ef,
        periods=int(periods),
        converged=bool(ok),
        q_end=qe,
        v_end=ve,
    )
    if t_bad >= 0:
        raise SolveError(
            f"time integration at {freq:.6g} Hz: Newton did not converge at the step "
            f"t = {t_bad:.6g} s (period {periods + 1}); the step is rejected (more "
            "steps_per_period may help)",
            partial=res,
        )
    if not ok:
        raise SolveError(
            f"time integration at {freq:.6g} Hz did not reach a periodic response "
            f"within {max_periods} periods (tol {tol:g})",
            partial=res,
        )
    return res
