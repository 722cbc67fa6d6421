"""Run-up from rest: time integration of a reduced rig, condensed onto its contacts.

The harmonic balance finds *a* periodic solution; with friction there can be
many (any stuck state inside the friction cone is an equilibrium), and
which one a damper reaches depends on its history. A damper squeezed by the
out-of-phase motion of its platforms can ratchet: it slips where the normal
load is low, cannot slip back where it is high, climbs into its groove and
sticks there with a raised normal load. :func:`runup` answers which state a
run-up from the static equilibrium reaches, for models too large for the
dense reference of :mod:`.timeint` (a few hundred DOFs, dozens of pairs).

Newmark's average-acceleration rule with a fixed step ``T / steps_per_period``
(as :mod:`.timeint`); each step is condensed onto the contact DOFs. With
``Kh = K + 2/dt C + 4/dt^2 M`` factorised once, ``A = W Kh^-1`` and
``G = A W^T``, the contact displacements ``u = W q`` of a step solve

    u = W Kh^-1 r - G f(u)

(``r`` the Newmark right-hand side, ``f`` the contact law of
:mod:`workbench.contact.laws`, the same ``step`` the harmonic balance
marches) by Newton's method on ``3 n_pairs`` unknowns with the law's tangent (when
it does not converge in 60 iterations, again from the last step's state
with the step halved until the residual falls: near a slip threshold the
plain iteration can cycle between stick and slip);
then ``q = Kh^-1 r - A^T f``. A step whose Newton does not converge stops
the run (:class:`SolveError` with what was computed as ``partial``).

Per period it records the output's mean and harmonic-1 amplitude, the
pairs' mean normal load over their preload and the slipping and separated
samples: enough to see the amplitude build up, slip begin and the mean
drift (:class:`RunUp`). The excitation can be ramped in over
``ramp_periods``; the state at the end is kept so a run can be continued.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit

from ...contact import get_law
from ...contact.march import specialise
from ...errors import InputError, SolveError, check_int, check_range
from ..core.ports import excitation_vector, observation
from ..core.system import System


@dataclass
class RunUp:
    """Period-by-period record of a run-up at one frequency (see the module docstring)."""

    freq_hz: float
    level: float
    mean: np.ndarray  # (n_periods, n_out) mean of each output over the period, m
    h1: np.ndarray  # (n_periods, n_out) harmonic-1 amplitude of each output, m
    normal_ratio: np.ndarray  # (n_periods, n_pairs) mean normal load / preload N0 (-)
    slip_samples: np.ndarray  # (n_periods,) samples x pairs slipping in the period
    sep_samples: np.ndarray  # (n_periods,) samples x pairs separated in the period
    state: dict  # end state {q, v, a, law}: pass as ``start`` to continue
    last: np.ndarray | None = None  # (steps_per_period, n_out) outputs over the last period, m

    @property
    def n_periods(self) -> int:
        return int(self.h1.shape[0])


step = None  # the law's step: bound per law by contact.march.specialise


@njit(cache=True)
def _newton_matrix(J, G, Kt):
    """``J = I + G Kt`` in place: the Jacobian of the contact residual ``u - ul + G f(u)``
    (``Kt`` (n_el, 3, 3): each element's ``df/du``)."""
    J[:, :] = 0.0
    for i in range(J.shape[0]):
        J[i, i] = 1.0
    for e in range(Kt.shape[0]):
        for aa in range(3):
            for bb in range(3):
                kab = Kt[e, aa, bb]
                if kab != 0.0:
                    J[:, 3 * e + bb] += G[:, 3 * e + aa] * kab


def _runup_py(
    ns, Kinv, A, G, Wd, C, M, mu, kt1, kt2, kn, n0, lp, fs, fc, fsn, omega, spp, p0, n_periods,
    ramp, O, q, v, a, state, ybuf, nbuf, slip, sep,
):  # fmt: skip
    n_el = Wd.shape[0] // 3
    m = 3 * n_el
    dt = 2.0 * np.pi / omega / spp
    beta, gamma = 0.25, 0.5
    s_new = np.zeros((n_el, ns))
    f = np.zeros((n_el, 3))
    Kt = np.zeros((n_el, 3, 3))
    Fs = np.zeros((3, ns))
    Su = np.zeros((ns, 3))
    Ss = np.zeros((ns, ns))
    J = np.zeros((m, m))
    flags = np.zeros(n_el, dtype=np.int64)
    for p in range(n_periods):
        for j in range(spp):
            t = ((p0 + p) * spp + j + 1) * dt
            r = 1.0
            if ramp > 0:
                r = min(1.0, t * omega / (2.0 * np.pi * ramp))
            load = fs + r * (fc * np.cos(omega * t) + fsn * np.sin(omega * t))
            rhs = (
                load
                + M @ (q / (beta * dt * dt) + v / (beta * dt) + (0.5 / beta - 1.0) * a)
                + C @ ((gamma / (beta * dt)) * q + (gamma / beta - 1.0) * v
                       + dt * (0.5 * gamma / beta - 1.0) * a)
            )  # fmt: skip
            ql = Kinv @ rhs
            ul = Wd @ ql
            u = Wd @ q
            ok = False
            for _ in range(60):
                uu = u.reshape(n_el, 3)
                for e in range(n_el):
                    step(uu[e], state[e], mu[e], kt1[e], kt2[e], kn[e], n0[e], lp[e], True,
                         f[e], s_new[e], Kt[e], Fs, Su, Ss)  # fmt: skip
                res = u - ul + G @ f.ravel()
                _newton_matrix(J, G, Kt)
                du = np.linalg.solve(J, -res)
                u = u + du
                if np.abs(du).max() <= 1e-11 * (max(np.abs(u).max(), np.abs(ul).max()) + 1e-300):
                    ok = True
                    break
            if not ok:
                # the plain iteration can cycle between stick and slip near a threshold:
                # again from the last step's state, with the step halved until |res| falls
                u = Wd @ q
                for _ in range(200):
                    uu = u.reshape(n_el, 3)
                    for e in range(n_el):
                        step(uu[e], state[e], mu[e], kt1[e], kt2[e], kn[e], n0[e], lp[e], True,
                             f[e], s_new[e], Kt[e], Fs, Su, Ss)  # fmt: skip
                    res = u - ul + G @ f.ravel()
                    _newton_matrix(J, G, Kt)
                    du = np.linalg.solve(J, -res)
                    if np.abs(du).max() <= 1e-11 * (
                        max(np.abs(u).max(), np.abs(ul).max()) + 1e-300
                    ):
                        u = u + du
                        ok = True
                        break
                    rn = np.linalg.norm(res)
                    lam = 1.0
                    for _b in range(40):
                        ut = u + lam * du
                        ut3 = ut.reshape(n_el, 3)
                        for e in range(n_el):
                            step(ut3[e], state[e], mu[e], kt1[e], kt2[e], kn[e], n0[e], lp[e],
                                 False, f[e], s_new[e], Kt[e], Fs, Su, Ss)  # fmt: skip
                        if np.linalg.norm(ut - ul + G @ f.ravel()) < rn:
                            break
                        lam *= 0.5
                    u = ut
            if not ok:
                return p
            uu = u.reshape(n_el, 3)
            for e in range(n_el):
                flags[e] = step(uu[e], state[e], mu[e], kt1[e], kt2[e], kn[e], n0[e], lp[e],
                                False, f[e], s_new[e], Kt[e], Fs, Su, Ss)  # fmt: skip
                if flags[e] == 1:
                    slip[p] += 1
                elif flags[e] == 2:
                    sep[p] += 1
                nbuf[p, e] += -f[e, 2] / spp
            qn = ql - A.T @ f.ravel()
            an = (qn - q) / (beta * dt * dt) - v / (beta * dt) - (0.5 / beta - 1.0) * a
            vn = v + dt * ((1.0 - gamma) * a + gamma * an)
            state[:, :] = s_new
            q[:] = qn
            v[:] = vn
            a[:] = an
            ybuf[p, j] = O @ q
    return n_periods


def runup(
    system: System,
    f1: np.ndarray,
    level: float,
    freq_hz: float,
    outputs: object = None,
    periods: int = 100,
    steps_per_period: int = 128,
    ramp_periods: float = 0.0,
    start: dict | None = None,
    progress=None,
    chunk: int = 10,
) -> RunUp:
    """Integrate ``level * Re(f1 exp(i w t))`` at ``freq_hz`` from rest for ``periods`` periods.

    ``start``: the ``state`` of an earlier :class:`RunUp` to continue it
    (default: rest at the static equilibrium ``u = 0``, every slider at
    zero force). ``ramp_periods``: the excitation grows linearly from 0
    over that many periods (0: switched on at once). ``progress(done,
    total)`` is called every ``chunk`` periods. Raises :class:`SolveError`
    (``partial``: the periods done) when a step's Newton does not converge.
    """
    freq = check_range("freq_hz", freq_hz, 0.0, lo_open=True, unit="Hz")
    level = check_range("level", level, 0.0)
    periods = check_int("periods", periods, 1)
    spp = check_int("steps_per_period", steps_per_period, 16)
    ramp = check_range("ramp_periods", ramp_periods, 0.0, unit="periods")
    el = system.contacts
    if el is None or not el.n_el:
        raise InputError("system.contacts", None, "a model with contact pairs")
    law = get_law(el.law)
    n = system.n
    C = system.damping_matrix()
    Wd = el.W.toarray()
    n_el = el.n_el
    omega = 2.0 * np.pi * freq
    dt = 1.0 / freq / spp
    Kh = system.K + (2.0 / dt) * C + (4.0 / (dt * dt)) * system.M
    Kinv = np.linalg.inv(Kh)
    A = Wd @ Kinv
    G = A @ Wd.T
    F = level * excitation_vector(system, f1)
    fs = system.total_static_force()
    O = observation(system, outputs)
    arrs = [np.ascontiguousarray(x, dtype=float) for x in (el.mu, el.kt1, el.kt2, el.kn, el.n0)]
    arrs.append(el.lp)  # the law's own parameters per element
    if start is None:
        q, v = np.zeros(n), np.zeros(n)
        state = np.zeros((n_el, law.n_state))
        f0 = np.zeros((n_el, 3))
        f0[:, 2] = -el.n0
        a = np.linalg.solve(system.M, fs - Wd.T @ f0.ravel())
        p0 = 0
    else:
        if start.get("law") != law.name or np.shape(start["q"]) != (n,):
            raise InputError(
                "start",
                "a RunUp state",
                f"the end state of a run-up of this model ({law.name} law, {n} DOFs)",
            )
        q, v, a = (np.array(start[k], dtype=float) for k in ("q", "v", "a"))
        state = np.array(start["s"], dtype=float)
        p0 = int(start["periods"])
    kernel = specialise(_runup_py, law, "_runup")
    n_out = O.shape[0]
    ys, ns_, sl, sp_ = [], [], [], []
    done = 0
    while done < periods:
        k = min(chunk, periods - done)
        ybuf = np.zeros((k, spp, n_out))
        nbuf = np.zeros((k, n_el))
        slip = np.zeros(k, dtype=np.int64)
        sep = np.zeros(k, dtype=np.int64)
        got = kernel(law.n_state, Kinv, A, G, Wd, C, system.M, *arrs, fs, F.real.copy(),
                     -F.imag.copy(), omega, spp, p0 + done, k, ramp, O, q, v, a, state,
                     ybuf, nbuf, slip, sep)  # fmt: skip
        ys.append(ybuf[:got]), ns_.append(nbuf[:got]), sl.append(slip[:got]), sp_.append(sep[:got])
        done += got
        if got < k:
            res = _record(freq, level, ys, ns_, sl, sp_, el.n0, q, v, a, state, law, p0 + done)
            raise SolveError(
                f"run-up at {freq:.6g} Hz: Newton did not converge in period {p0 + done + 1}; "
                "the step is rejected (more steps_per_period may help)",
                partial=res,
            )
        if progress is not None:
            progress(done, periods)
    return _record(freq, level, ys, ns_, sl, sp_, el.n0, q, v, a, state, law, p0 + done)


def _record(freq, level, ys, ns_, sl, sp_, n0, q, v, a, state, law, periods) -> RunUp:
    y = np.concatenate(ys) if ys else np.zeros((0, 1, 1))
    spp = y.shape[1]
    t = 2.0 * np.pi * np.arange(1, spp + 1) / spp
    h1 = np.abs(np.einsum("psk,s->pk", y, np.exp(-1j * t))) * 2.0 / max(spp, 1)
    return RunUp(
        freq_hz=freq,
        level=level,
        mean=y.mean(axis=1),
        h1=h1,
        normal_ratio=np.concatenate(ns_) / n0[None, :] if ns_ else np.zeros((0, n0.size)),
        slip_samples=np.concatenate(sl) if sl else np.zeros(0, int),
        sep_samples=np.concatenate(sp_) if sp_ else np.zeros(0, int),
        state=dict(
            q=q.copy(), v=v.copy(), a=a.copy(), s=state.copy(), law=law.name, periods=periods
        ),
        last=y[-1].copy() if y.shape[0] else None,
    )
