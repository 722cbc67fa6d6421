"""A Jenkins element with a circular slip limit ``|T| <= mu N`` in the tangent plane.

State ``s = [T1, T2, u1, u2]`` as for the decoupled law; the trial force
``T* = T + K_t (u - u_prev)`` (a vector) is scaled back onto the circle
``|T| = mu N`` when it lies outside (radial return). Unlike the decoupled
law its loop can take many periods to settle near the slip threshold.

Its periodic state can depend on where the period starts: a loop that
slips in one tangential direction leaves the other free (on 2000 random
periodic motions the start moved the force by up to 0.51 mu N0; 0.74 on
stuck motions with a large mean; ``tests/test_march_history.py``). A
proportional growth of the motion from rest before the periodic march
(``growth`` of :func:`workbench.contact.march.march`) removes that, about
as 1 / growth, but against a slowly ramped run-up the march from rest is
3.5-10 times closer (docs/notes/mean_position.md), so the march from rest
stays this law's rule and its results carry that dependence.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from . import SLIP_TOL
from ._common import begin

NAME = "circular"
N_STATE = 4


@njit(cache=True)
def step(u, s, mu, kt1, kt2, kn, n0, lp, want_jac, f, s_new, Fu, Fs, Su, Ss):
    N = begin(u, kn, n0, want_jac, f, s_new, Fu, Fs, Su, Ss)
    if N <= 0.0:
        return 2
    lim = mu * N
    Tp1 = s[0] + kt1 * (u[0] - s[2])
    Tp2 = s[1] + kt2 * (u[1] - s[3])
    nrm = np.sqrt(Tp1 * Tp1 + Tp2 * Tp2)
    flag = 0
    if nrm <= lim:
        f[0] = Tp1
        f[1] = Tp2
        if want_jac:
            Fu[0, 0] = kt1
            Fu[1, 1] = kt2
            Fs[0, 0] = 1.0
            Fs[1, 1] = 1.0
            Fs[0, 2] = -kt1
            Fs[1, 3] = -kt2
    else:
        if nrm - lim > SLIP_TOL * lim:
            flag = 1
        e1 = Tp1 / nrm
        e2 = Tp2 / nrm
        f[0] = lim * e1
        f[1] = lim * e2
        if want_jac:
            g = lim / nrm
            # d(T)/d(Tp) = g (I - e e^T); dTp/du = diag(kt), dTp/ds = [I, -diag(kt)]
            P11 = g * (1.0 - e1 * e1)
            P12 = -g * e1 * e2
            P22 = g * (1.0 - e2 * e2)
            Fu[0, 0] = P11 * kt1
            Fu[0, 1] = P12 * kt2
            Fu[1, 0] = P12 * kt1
            Fu[1, 1] = P22 * kt2
            Fu[0, 2] = -mu * kn * e1
            Fu[1, 2] = -mu * kn * e2
            Fs[0, 0] = P11
            Fs[0, 1] = P12
            Fs[1, 0] = P12
            Fs[1, 1] = P22
            Fs[0, 2] = -P11 * kt1
            Fs[0, 3] = -P12 * kt2
            Fs[1, 2] = -P12 * kt1
            Fs[1, 3] = -P22 * kt2
    s_new[0] = f[0]
    s_new[1] = f[1]
    if want_jac:
        for a in range(2):
            for b in range(3):
                Su[a, b] = Fu[a, b]
            for b in range(4):
                Ss[a, b] = Fs[a, b]
    return flag
