"""The time-domain contact law, compiled with numba and vectorised over elements.

Per element, with the local relative displacement ``u = [u1, u2, un]``
(metres, ``un > 0`` opening) sampled at ``t_j``:

* normal force ``N_j = max(0, N0 - kn un_j)`` (N, compressive positive;
  DESIGN.md writes ``N0 + kn un`` with ``un`` positive into the contact, the
  same law in the sign convention of ``workbench.geometry.records``);
* tangential force, per axis ``a`` (decoupled law): predictor
  ``T* = T_{j-1} + kt_a (u_a,j - u_a,j-1)``, corrector ``T = clip(T*, +-mu N_j)``;
  circular law: ``T* `` as a vector, scaled back onto ``|T| = mu N_j`` when
  it lies outside; separated (``N_j = 0``): ``T = 0`` and the slider follows;
* the element starts from rest (slider at ``u = 0``), so an element that
  never slips carries exactly ``kt u``: the stuck linear limit.

The force on the coordinates is ``f = [T1, T2, -N]`` (a restoring force:
the equation of motion reads ``M q'' + C q' + K q + W^T f = p``).

:func:`aft_march` runs the law over two periods of given samples (the
second is the converged loop: after any slip or separation the state no
longer depends on the start) and returns the harmonics of the force and,
exactly, their derivative with respect to the harmonics of ``u``
(propagated through the steps). :func:`law_step` is the same law for one
time step with its consistent tangent, for the time-integration reference.
"""

from __future__ import annotations

import numpy as np
from numba import njit

STUCK, STICK_SLIP, PARTIAL_SEPARATION, FULL_SEPARATION = 0, 1, 2, 3

# A sample counts as slipping (for the status only; the force is clipped
# either way) when the predictor exceeds the slip limit by more than this
# fraction of it. In the converged period an element that slipped only
# while the march started (elastic shakedown) touches its limit again to
# round-off, ~1e-15 relative, without slipping: it is stuck.
SLIP_TOL = 1e-9
STATUS_NAMES = ("stuck", "stick-slip", "partial separation", "full separation")


@njit(cache=True)
def _aft_march(u, E, P, mu, kt1, kt2, kn, n0, law, want_jac, f, F, J, n_slip, n_sep, contact):
    n_el, nt, _ = u.shape
    nh = E.shape[1]
    m = 3 * nh
    dT1 = np.zeros(m)
    dT2 = np.zeros(m)
    dN = np.zeros(m)
    dp1 = np.zeros(m)
    dp2 = np.zeros(m)
    for e in range(n_el):
        # derivative blocks accumulated below: [c0, c1) over (t1, t2, n) x nh
        if law == 0:
            c0_1, c1_1 = 0, nh
            c0_2, c1_2 = nh, 2 * nh
        else:
            c0_1, c1_1 = 0, (3 * nh if kn[e] != 0.0 else 2 * nh)
            c0_2, c1_2 = 0, c1_1
        T1 = 0.0
        T2 = 0.0
        up1 = 0.0
        up2 = 0.0
        dT1[:] = 0.0
        dT2[:] = 0.0
        jprev = -1
        ns = 0
        nsep = 0
        for p in range(2):
            for j in range(nt):
                u1 = u[e, j, 0]
                u2 = u[e, j, 1]
                un = u[e, j, 2]
                N = n0[e] - kn[e] * un
                closed = N > 0.0
                if not closed:
                    N = 0.0
                Tp1 = T1 + kt1[e] * (u1 - up1)
                Tp2 = T2 + kt2[e] * (u2 - up2)
                if want_jac:
                    for c in range(m):
                        dp1[c] = dT1[c]
                        dp2[c] = dT2[c]
                        dN[c] = 0.0
                    for h in range(nh):
                        de = E[j, h] - (E[jprev, h] if jprev >= 0 else 0.0)
                        dp1[h] += kt1[e] * de
                        dp2[nh + h] += kt2[e] * de
                        if closed:
                            dN[2 * nh + h] = -kn[e] * E[j, h]
                slipping = False
                if not closed:
                    T1 = 0.0
                    T2 = 0.0
                    if want_jac:
                        dT1[:] = 0.0
                        dT2[:] = 0.0
                else:
                    lim = mu[e] * N
                    if law == 0:
                        if abs(Tp1) <= lim:
                            T1 = Tp1
                            if want_jac:
                                dT1[:] = dp1
                        else:
                            s = 1.0 if Tp1 > 0.0 else -1.0
                            T1 = s * lim
                            slipping = slipping or abs(Tp1) - lim > SLIP_TOL * lim
                            if want_jac:
                                for c in range(m):
                                    dT1[c] = s * mu[e] * dN[c]
                        if abs(Tp2) <= lim:
                            T2 = Tp2
                            if want_jac:
                                dT2[:] = dp2
                        else:
                            s = 1.0 if Tp2 > 0.0 else -1.0
                            T2 = s * lim
                            slipping = slipping or abs(Tp2) - lim > SLIP_TOL * lim
                            if want_jac:
                                for c in range(m):
                                    dT2[c] = s * mu[e] * dN[c]
                    else:
                        nrm = np.sqrt(Tp1 * Tp1 + Tp2 * Tp2)
                        if nrm <= lim:
                            T1 = Tp1
                            T2 = Tp2
                            if want_jac:
                                dT1[:] = dp1
                                dT2[:] = dp2
                        else:
                            slipping = nrm - lim > SLIP_TOL * lim
                            e1 = Tp1 / nrm
                            e2 = Tp2 / nrm
                            T1 = lim * e1
                            T2 = lim * e2
                            if want_jac:
                                g = lim / nrm
                                for c in range(m):
                                    proj = e1 * dp1[c] + e2 * dp2[c]
                                    dT1[c] = mu[e] * e1 * dN[c] + g * (dp1[c] - e1 * proj)
                                    dT2[c] = mu[e] * e2 * dN[c] + g * (dp2[c] - e2 * proj)
                up1 = u1
                up2 = u2
                jprev = j
                if p == 1:
                    f[e, j, 0] = T1
                    f[e, j, 1] = T2
                    f[e, j, 2] = -N
                    contact[e, j] = closed
                    if slipping:
                        ns += 1
                    if not closed:
                        nsep += 1
                    for h in range(nh):
                        ph = P[h, j]
                        F[e, 0, h] += ph * T1
                        F[e, 1, h] += ph * T2
                        F[e, 2, h] -= ph * N
                        if want_jac and ph != 0.0:
                            # only the blocks that can be non-zero: T_a depends on u_a (and on
                            # u_b for the circular law) and on un when kn > 0; N on un only
                            for c in range(c0_1, c1_1):
                                J[e, 0, h, c] += ph * dT1[c]
                            for c in range(c0_2, c1_2):
                                J[e, 1, h, c] += ph * dT2[c]
                            if kn[e] != 0.0:
                                for c in range(2 * nh, m):
                                    J[e, 2, h, c] -= ph * dN[c]
                                if law == 0:
                                    for c in range(2 * nh, m):
                                        J[e, 0, h, c] += ph * dT1[c]
                                        J[e, 1, h, c] += ph * dT2[c]
        n_slip[e] = ns
        n_sep[e] = nsep


def aft_march(
    u: np.ndarray,
    E: np.ndarray,
    P: np.ndarray,
    mu: np.ndarray,
    kt1: np.ndarray,
    kt2: np.ndarray,
    kn: np.ndarray,
    n0: np.ndarray,
    law: int,
    want_jac: bool = True,
) -> dict[str, np.ndarray]:
    """March the law over two periods of samples ``u`` (n_el, nt, 3) in metres.

    ``E`` (nt, nh) synthesises the samples from harmonics, ``P`` (nh, nt)
    analyses them (see :mod:`workbench.hbm.fourier`). Returns a dict with

    * ``f`` (n_el, nt, 3): force samples ``[T1, T2, -N]`` (N) of the converged period;
    * ``F`` (n_el, 3, nh): their harmonics ``P @ f``;
    * ``J`` (n_el, 3, nh, 3, nh): ``dF[e, a, h] / dU[e, b, c]`` (N/m), or None;
    * ``n_slip``, ``n_sep`` (n_el,): samples slipping / separated in that period;
    * ``contact`` (n_el, nt): the contact is closed (N > 0) at each sample.
    """
    u = np.ascontiguousarray(u, dtype=float)
    n_el, nt, _ = u.shape
    nh = E.shape[1]
    f = np.zeros((n_el, nt, 3))
    F = np.zeros((n_el, 3, nh))
    J = np.zeros((n_el, 3, nh, 3 * nh)) if want_jac else np.zeros((1, 3, 1, 3))
    n_slip = np.zeros(n_el, dtype=np.int64)
    n_sep = np.zeros(n_el, dtype=np.int64)
    contact = np.zeros((n_el, nt), dtype=np.bool_)
    _aft_march(
        u,
        np.ascontiguousarray(E, dtype=float),
        np.ascontiguousarray(P, dtype=float),
        mu,
        kt1,
        kt2,
        kn,
        n0,
        int(law),
        bool(want_jac),
        f,
        F,
        J,
        n_slip,
        n_sep,
        contact,
    )
    return dict(
        f=f,
        F=F,
        J=J.reshape(n_el, 3, nh, 3, nh) if want_jac else None,
        n_slip=n_slip,
        n_sep=n_sep,
        contact=contact,
    )


def march_samples(u: np.ndarray, elements) -> dict[str, np.ndarray]:
    """The law over two periods of samples ``u`` (n_el, nt, 3) of a :class:`ContactElements`.

    Same output as :func:`aft_march` without harmonics (``F``, ``J`` unused).
    """
    nt = np.asarray(u).shape[1]
    E = np.zeros((nt, 1))
    P = np.zeros((1, nt))
    return aft_march(
        u,
        E,
        P,
        elements.mu,
        elements.kt1,
        elements.kt2,
        elements.kn,
        elements.n0,
        elements.law_code,
        want_jac=False,
    )


def classify(n_slip: np.ndarray, n_sep: np.ndarray, nt: int) -> np.ndarray:
    """Status per element over a period from the counts of slipping/separated samples.

    0 stuck (never slips, never separates), 1 stick-slip, 2 partial
    separation (separated during part of the period), 3 full separation.
    """
    n_slip = np.asarray(n_slip)
    n_sep = np.asarray(n_sep)
    s = np.where(n_slip > 0, STICK_SLIP, STUCK)
    s = np.where(n_sep > 0, PARTIAL_SEPARATION, s)
    s = np.where(n_sep >= nt, FULL_SEPARATION, s)
    return s.astype(np.int8)


@njit(cache=True)
def law_step(u, state, mu, kt1, kt2, kn, n0, law, f, Kt, flags):
    """One time step of every element from the converged ``state`` of the previous step.

    ``u`` (n_el, 3) trial local displacement (m); ``state`` (n_el, 4) holds
    ``[T1, T2, u1, u2]`` of the previous step (updated in place by the caller
    when the step is accepted: see :func:`accept_step`). Writes the force
    ``f`` (n_el, 3) = ``[T1, T2, -N]`` and the consistent tangent
    ``Kt`` (n_el, 3, 3) = ``df/du`` (N/m) and ``flags`` (n_el,): 0 stuck,
    1 slipping, 2 separated. Returns the number of slipping elements.
    """
    n_el = u.shape[0]
    nslip = 0
    for e in range(n_el):
        for a in range(3):
            for b in range(3):
                Kt[e, a, b] = 0.0
        flags[e] = 0
        N = n0[e] - kn[e] * u[e, 2]
        if N <= 0.0:
            f[e, 0] = 0.0
            f[e, 1] = 0.0
            f[e, 2] = 0.0
            flags[e] = 2
            continue
        f[e, 2] = -N
        Kt[e, 2, 2] = kn[e]
        Tp1 = state[e, 0] + kt1[e] * (u[e, 0] - state[e, 2])
        Tp2 = state[e, 1] + kt2[e] * (u[e, 1] - state[e, 3])
        lim = mu[e] * N
        if law == 0:
            if abs(Tp1) <= lim:
                f[e, 0] = Tp1
                Kt[e, 0, 0] = kt1[e]
            else:
                s = 1.0 if Tp1 > 0.0 else -1.0
                f[e, 0] = s * lim
                Kt[e, 0, 2] = -s * mu[e] * kn[e]
                nslip += 1
                flags[e] = 1
            if abs(Tp2) <= lim:
                f[e, 1] = Tp2
                Kt[e, 1, 1] = kt2[e]
            else:
                s = 1.0 if Tp2 > 0.0 else -1.0
                f[e, 1] = s * lim
                Kt[e, 1, 2] = -s * mu[e] * kn[e]
                nslip += 1
                flags[e] = 1
        else:
            nrm = np.sqrt(Tp1 * Tp1 + Tp2 * Tp2)
            if nrm <= lim:
                f[e, 0] = Tp1
                f[e, 1] = Tp2
                Kt[e, 0, 0] = kt1[e]
                Kt[e, 1, 1] = kt2[e]
            else:
                e1 = Tp1 / nrm
                e2 = Tp2 / nrm
                f[e, 0] = lim * e1
                f[e, 1] = lim * e2
                g = lim / nrm
                Kt[e, 0, 0] = g * (1.0 - e1 * e1) * kt1[e]
                Kt[e, 0, 1] = -g * e1 * e2 * kt2[e]
                Kt[e, 1, 0] = -g * e2 * e1 * kt1[e]
                Kt[e, 1, 1] = g * (1.0 - e2 * e2) * kt2[e]
                Kt[e, 0, 2] = -mu[e] * kn[e] * e1
                Kt[e, 1, 2] = -mu[e] * kn[e] * e2
                nslip += 1
                flags[e] = 1
    return nslip


@njit(cache=True)
def accept_step(u, f, state):
    """Store the accepted step as the next step's history: ``[T1, T2, u1, u2]``."""
    for e in range(u.shape[0]):
        state[e, 0] = f[e, 0]
        state[e, 1] = f[e, 1]
        state[e, 2] = u[e, 0]
        state[e, 3] = u[e, 1]
